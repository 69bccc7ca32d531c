//! The integer RGBA8 resolve of HT heads and tails (`crate::resolve::int::ht_rgba8`,
//! `docs/layout.md`, "Integer resolve of HT") for 8 pixels: one pixel per 32-bit lane, in
//! the lane order of `src/lanes/layout.rs` (`POSITION`), every step the scalar definition's, so
//! the bytes are the scalar's. The two exact integer divisions are computed as f32 divisions
//! (both operands below 2^24, the divisor at least 1: the truncated correctly rounded quotient
//! is the integer quotient; `exact_div_is_the_integer_division` tests it).

use crate::lanes::LANES;
use crate::lanes::layout::{layer_words, tail_fields, unpermute};
use crate::resolve::int::{self, IntBackground};
use crate::row::Row;
use crate::tail::TailFormat;
use bytemuck::cast;
use wide::{f32x8, i16x8, i16x16, i16x32, i32x8, u16x8, u16x16, u16x32, u32x8};

// Every product below is a 16-bit one (`wide` has no 32-bit lane multiply or unsigned
// 32-bit min on SSE2, and its emulation lane by lane dominated the resolve: docs/performance.md,
// resolves): `pmaddwd`
// (`i16x16::dot`) where both factors are below 2^15, `pmulhuw` and `pmullw` where they are
// below 2^16. The tail's Horner sums and bit products run in 16-bit lanes, 8 pixels in one
// 128-bit register; values of 17 bits (T, the first factor of the products) keep their top
// bit as a mask beside them.

/// All lanes `v`.
#[inline(always)]
fn k(v: u32) -> u32x8 {
    u32x8::splat(v)
}

/// All 16-bit lanes `v`.
#[inline(always)]
fn w(v: u16) -> u16x8 {
    u16x8::splat(v)
}

/// `x * y` per lane for `x, y` in `0..=32767` (`pmaddwd`: the high halves of the lanes are
/// zero, so each lane's pair sums one product).
#[inline(always)]
fn mul15(x: u32x8, y: u32x8) -> u32x8 {
    cast::<i32x8, u32x8>(cast::<u32x8, i16x16>(x).dot(cast::<u32x8, i16x16>(y)))
}

/// `sum_k c[k] y^k - c[0]` per 16-bit lane (type `$w`) as the rounded Horner sum of `int`
/// computes it (`x = c[n - 1]`, then `x = c[k] + q16(x, y)` down to `k = 1`, then
/// `q16(x, y)`), from `y2 = 2 y` (at most 65535): `q16(x, y) = (mulhi(x, 2 y) + 1) >> 1`
/// (`mulhi(x, 2y)` is `floor(x y / 2^15)`), and for `k >= 2` the coefficient folds in as
/// `(mulhi + 2 c + 1) >> 1`, below 2^16 for every operand of `int::{H, EXP, PSI}` (largest
/// 54164, `h` at `k = 2`): one multiply, one add and one shift per step (`pavgw`).
macro_rules! horner_tail {
    ($w:ty, $c:expr, $y2:expr) => {{
        let (c, y2): (&[u32], $w) = ($c, $y2);
        let n = c.len();
        let mut x = <$w>::splat(c[n - 1] as u16);
        for &ck in c[2..n - 1].iter().rev() {
            x = (x.mul_keep_high(y2) + <$w>::splat((2 * ck + 1) as u16)) >> 1;
        }
        x = ((x.mul_keep_high(y2) + <$w>::splat(1)) >> 1) + <$w>::splat(c[1] as u16);
        (x.mul_keep_high(y2) + <$w>::splat(1)) >> 1
    }};
}

/// `e_r - EXP[0]` at `y = 32768` (`2 y` does not fit a 16-bit lane there): 25787.
#[expect(clippy::cast_possible_truncation, reason = "below 2^16")]
const ED_HALF: u16 = {
    let mut e = int::EXP[6];
    let mut k = 6;
    while k > 0 {
        k -= 1;
        e = int::EXP[k] + (e * 32768 + 32768) / 65536;
    }
    (e - int::EXP[0]) as u16
};

/// 32-bit lanes in `0..=32767` to 16-bit lanes (`packssdw`; larger lanes become 32767).
#[inline(always)]
fn narrow(x: u32x8) -> u16x8 {
    cast::<i16x8, u16x8>(i16x8::from_i32x8_saturate(cast(x)))
}

/// 16-bit lanes to 32-bit lanes, zero-extended.
#[inline(always)]
fn widen(x: u16x8) -> u32x8 {
    cast::<i32x8, u32x8>(i32x8::from_u16x8(x))
}

/// A 16-bit lane mask to a 32-bit lane mask.
#[inline(always)]
fn widen_mask(x: u16x8) -> u32x8 {
    cast::<i32x8, u32x8>(i32x8::from_i16x8(cast(x)))
}

/// `min(a, b)` per 16-bit lane, both in `0..=32767`.
#[inline(always)]
fn min15(a: u16x8, b: u16x8) -> u16x8 {
    cast::<i16x8, u16x8>(cast::<u16x8, i16x8>(a).min(cast(b)))
}

/// `floor(a / b)` for `a < 2^24`, `1 <= b < 2^24`: the f32 quotient, correctly rounded and
/// truncated, is the integer quotient (half an ulp of `a / b` is below `1 / b`, the distance
/// from a non-integer quotient to the next integer).
#[cfg(test)]
#[inline(always)]
pub(in crate::lanes) fn exact_div(a: u32x8, b: u32x8) -> u32x8 {
    div_f32(f32x8::from_i32x8(cast(a)), f32x8::from_i32x8(cast(b)))
}

/// [`exact_div`] of operands already converted (exact integers in f32).
#[inline(always)]
fn div_f32(a: f32x8, b: f32x8) -> u32x8 {
    cast::<i32x8, u32x8>((a / b).fast_trunc_int())
}

/// `int::tail` per lane: `(T, g)` in Q16.
#[cfg(test)]
#[inline(always)]
pub(in crate::lanes) fn tail(alpha: u32x8, count: u32x8) -> (u32x8, u32x8) {
    let (t, g, _) = tail_parts(alpha, count);
    (t, g)
}

/// The tail's inputs in 16-bit lanes (from its alpha sum and count in 32-bit lanes):
/// `[min(m, 32767), 65535 - min(m, 65535), min(max(count, 1), 32767), min(S_a, 4095)]`,
/// `m = (257 S_a) / max(count, 1)`, and `S_a` as f32.
#[inline(always)]
fn tail_inputs(alpha: u32x8, count: u32x8) -> ([u16x8; 4], f32x8) {
    let alpha_f = f32x8::from_i32x8(cast(alpha));
    // m = (257 S_a) / max(count, 1), both below 2^24 (257 S_a as an exact f32 product: in
    // integers LLVM makes `(S_a << 8) + S_a` a multiply, which SSE2 emulates).
    let m = div_f32(
        alpha_f * f32x8::splat(257.0),
        f32x8::from_i32x8(cast(count)).fast_max(f32x8::ONE),
    );
    // 65535 - min(m, 65535): `packssdw` of m - 32768 is min(m, 65535) - 32768 (m >= 0).
    let x = narrow(m - k(32768)) ^ w(0x7fff);
    let n = cast::<i16x8, u16x8>(cast::<u16x8, i16x8>(narrow(count)).max(i16x8::splat(1)));
    ([narrow(m), x, n, min15(narrow(alpha), w(4095))], alpha_f)
}

/// What the 32-bit end of the tail takes from its 16-bit lanes: `[min(T, 65535), T >> 16
/// (as a mask), h - H[0], T >> 1, ((T >> 1) psd + 16384) >> 15, the series mask]`.
type TailMid<W> = [W; 6];

/// The 16-bit part of `int::tail` (from [`tail_inputs`]) for 8 lanes (`u16x8`) or for 16
/// (`u16x16`: two spans at once, so that their two dependency chains, about 200 cycles
/// each, overlap).
macro_rules! tail_mid {
    ($name:ident, $w:ty, $i:ty) => {
        #[inline(always)]
        #[expect(
            clippy::cast_possible_truncation,
            reason = "the constants of `int` are below 2^16 where they are cut to 16-bit lanes"
        )]
        fn $name([ms, x, n, sa]: [$w; 4]) -> TailMid<$w> {
            let w = |v: u16| <$w>::splat(v);
            let gt = |a: $w, b: $w| cast::<$i, $w>(cast::<$w, $i>(a).simd_gt(cast::<$w, $i>(b)));
            let route_b = gt(ms, w(16384)); // !series
            let mm = cast::<$i, $w>(cast::<$w, $i>(ms).min(<$i>::splat(16384)));
            // h(m) = H[0] + hd.
            let hd = horner_tail!($w, &int::H, mm << 1);
            // u = (sa (65536 + 257 + hd) + 128) >> 8 = 256 (sa + hi) + ((lo + 128) >> 8),
            // with hi, lo the halves of sa (257 + hd) (below 2^26); then u = 256 s + r',
            // r' < 256.
            let hq = hd + w(257);
            let lo = sa * hq;
            let r = ((lo >> 1) + w(64)) >> 7; // (lo + 128) >> 8, in 0..=256
            let s = sa.mul_keep_high(hq) + sa + (r >> 8);
            let j = s >> 7; // u >> 15
            let ul: $w = ((s & w(127)) << 8) | (r & w(255)); // u & 32767
            let y = w(32768) - ul;
            let uu = ul | (gt(j, w(0)) & w(32767)); // min(u, 32767)
            // e_r - EXP[0], at most 25787.
            let ed = ul
                .simd_eq(w(0))
                .select(w(ED_HALF), horner_tail!($w, &int::EXP, y << 1));
            // zero = series ? u >= 786432 : n >= 64;  bits = zero ? 0 : (series ? j : n).
            let zero = route_b.select(gt(n, w(63)), gt(j, w(23)));
            let bits = route_b.select(n, j) & !zero;
            // p = p_lo + 65536 (hi & 1): e_r (up to 65537) on route A, 1 on route B. After
            // its first product a lane's p is below 2^16: q16(p, f) = q16(p_lo, f) + (hi & f).
            let e0 = int::EXP[0] as u16;
            let mut p = (w(e0) + ed) & !route_b;
            let mut hi = route_b | gt(ed, w(u16::MAX - e0));
            let mut b = x;
            // Bits above the largest lane's are zero in every lane: their steps change nothing.
            let top = bits.to_array().iter().fold(0, |a, &v| a | v);
            let steps = (u16::BITS - top.leading_zeros()) as usize;
            for (i, e_bit) in int::EXP_BITS.into_iter().enumerate().take(steps) {
                let bit = w(1 << i);
                let on = (bits & bit).simd_eq(bit);
                // Off lanes multiply by 0 and add p back: no select on the chain through p.
                let f = route_b.select(b, w(e_bit as u16)) & on;
                p = p.mul_keep_high(f) + ((f & hi) + (p & !on)) + ((p * f) >> 15);
                hi &= !on;
                b = b.mul_keep_high(b) + ((b * b) >> 15);
            }
            // T = zero ? 0 : min(p, 65536): t16 = min(T, 65535), top bit `hi`.
            let hi = hi & !zero;
            let t16 = (p & !zero) | hi;
            let psd = horner_tail!($w, &int::PSI, uu << 1); // psi - 65536, below 2^15
            // phi = ((T >> 1) psi + 16384) >> 15 = 2 th + ((th psd + 16384) >> 15), th = T >> 1.
            let th: $w = (t16 >> 1) + (hi & w(1));
            let c = (th.mul_keep_high(psd) << 1) + ((((th * psd) >> 1) + w(8192)) >> 14);
            [t16, hi, hd, th, c, !route_b & j.simd_eq(w(0))]
        }
    };
}

tail_mid!(tail_mid8, u16x8, i16x8);
tail_mid!(tail_mid16, u16x16, i16x16);
tail_mid!(tail_mid32, u16x32, i16x32);

/// The 32-bit end of `int::tail`: `(T, g, min(T, 65535))`.
#[inline(always)]
fn tail_end([t16, hi, hd, th, c, use_series]: TailMid<u16x8>, alpha_f: f32x8) -> (u32x8, u32x8, u16x8) {
    let t = widen(t16) + (widen(hi) & k(1));
    let phi = (widen(th) << 1) + widen(c);
    let l = (widen(hd) * phi + k(128)) >> 8;
    let g_series = phi + (((l << 8) - l + k(32768)) >> 16);
    // (65536 - T) 255 as an exact f32 product (below 2^24).
    let d = f32x8::from_i32x8(cast(k(int::Q16_ONE) - t)) * f32x8::splat(255.0);
    let g_div = div_f32(d, alpha_f.fast_max(f32x8::ONE));
    let g = widen_mask(use_series).select(g_series, g_div);
    (
        t,
        cast::<i32x8, u32x8>(cast::<u32x8, i32x8>(g).min(i32x8::splat(65536))),
        t16,
    )
}

/// `int::tail` per lane: `T`, `g`, and `min(T, 65535)` in 16-bit lanes.
#[inline(always)]
fn tail_parts(alpha: u32x8, count: u32x8) -> (u32x8, u32x8, u16x8) {
    let (inputs, alpha_f) = tail_inputs(alpha, count);
    tail_end(tail_mid8(inputs), alpha_f)
}

/// Whether `pmulhrsw` is native (SSSE3 and later): the head's factors and visibility are
/// then kept as they are, else doubled (`q15` from `pmulhuw`: the SSE2 form of the MLAB
/// integer resolve, `docs/layout.md`).
const MULHRS: bool = cfg!(target_feature = "ssse3");

/// A factor or visibility (at most 32767) as the head keeps it: doubled without `pmulhrsw`.
#[inline(always)]
fn keep(x: u16x8) -> u16x8 {
    if MULHRS { x } else { x << 1 }
}

/// The inverse of [`keep`].
#[inline(always)]
fn unkeep(x: u16x8) -> u16x8 {
    if MULHRS { x } else { x >> 1 }
}

/// `q15(x, y) = (x y + 16384) >> 15` per 16-bit lane from `x`, `y` as kept ([`keep`]; both at
/// most 32767): `pmulhrsw`, or `(mulhi(2 x, 2 y) + 1) >> 1` (`pmulhuw`, `pavgw`).
#[inline(always)]
fn q15k(x: u16x8, y: u16x8) -> u16x8 {
    if MULHRS {
        cast::<i16x8, u16x8>(cast::<u16x8, i16x8>(x).mul_scale_round(cast(y)))
    } else {
        (x.mul_keep_high(y) + w(1)) >> 1
    }
}

/// `q16(t, v)` per 16-bit lane for `t <= 65535` and `v <= 32767` as kept ([`keep`]), as kept:
/// `(mulhi(t, 2 v) + 1) >> 1`.
#[inline(always)]
fn q16k(t: u16x8, v: u16x8) -> u16x8 {
    let v2 = if MULHRS { v << 1 } else { v };
    keep((t.mul_keep_high(v2) + w(1)) >> 1)
}

/// The head of 8 HT pixels in 16-bit lanes, factors and visibility as kept ([`keep`]:
/// `128 c`, `floor(257 T / 2)`, `v`), 8 pixels in one 128-bit register: the three
/// accumulators and `v` as kept.
#[inline(always)]
#[expect(
    clippy::cast_possible_truncation,
    reason = "accumulator start and visibility below 2^15"
)]
fn head_lanes<const K: usize>(head: &[[Row; LANES]; K]) -> ([u16x8; 3], u16x8) {
    let high = w(0xff00);
    let mut acc = [w(int::ACC_START as u16); 3];
    let mut v = keep(w(int::VIS_ONE as u16));
    for layer in head {
        let words = cast::<u32x8, i32x8>(layer_words(layer));
        // [R | G << 8] and [B | T << 8] per pixel (`packssdw` of sign-extended halves).
        let rg = cast::<i16x8, u16x8>(i16x8::from_i32x8_truncate(words));
        let bt = cast::<i16x8, u16x8>(i16x8::from_i32x8_saturate(words >> 16));
        // 256 c, halved where kept as is.
        for (a, c) in acc.iter_mut().zip([rg << 8, rg & high, bt << 8]) {
            *a = add_sat(*a, q15k(if MULHRS { c >> 1 } else { c }, v));
        }
        let t = bt >> 8;
        let f = (t << 8) + t; // 257 T
        v = keep(q15k(if MULHRS { f >> 1 } else { f & w(0xfffe) }, v));
    }
    (acc, v)
}

/// `min(32767, a + b)` per 16-bit lane for `a, b` in `0..=32767` (`paddsw`).
#[inline(always)]
fn add_sat(a: u16x8, b: u16x8) -> u16x8 {
    cast::<i16x8, u16x8>(cast::<u16x8, i16x8>(a).saturating_add(cast(b)))
}

/// The tail added to the head's `(acc, v)` (`v` as kept): its color sums, `g` and
/// `min(T, 65535)`.
#[inline(always)]
fn add_tail((mut acc, vk): ([u16x8; 3], u16x8), sums: [u32x8; 3], (g, t16): (u32x8, u16x8)) -> ([u16x8; 3], u16x8) {
    // S_c g = 4 S_c (g >> 2) + S_c (g & 3) (`pmaddwd`: 4 S_c < 2^15, g <= 65536).
    let gq = (g >> 2) | ((g & k(3)) << 16);
    let v = widen(unkeep(vk));
    let v_hi = v << 16;
    for (a, s) in acc.iter_mut().zip(sums) {
        // [4 S_c, S_c] per lane; `4 S_c` shifted in 16-bit lanes, or LLVM makes the pair
        // one multiply by 65540 (emulated on SSE2, `vpmulld` on AVX2).
        let s4 = cast::<u16x16, u32x8>(cast::<u32x8, u16x16>(s) << 2);
        let l = (mul15(s4 | (s << 16), gq) + k(256)) >> 9;
        // l as the 16-bit pair (l & 32767, l >> 15): (l >> 15) v + q15(l & 32767, v),
        // saturated to 32767 by `packssdw`, then added with saturation.
        let pair = l + (l & k(!32767));
        let term = mul15(pair, v_hi) + ((mul15(pair, v) + k(16384)) >> 15);
        *a = add_sat(*a, narrow(term));
    }
    // q16(T, v) = q16(min(T, 65535), v) for v <= 32768.
    (acc, q16k(t16, vk))
}

/// The pixels of `(acc, v)` (`v` as kept) over the opaque background `bg` when `OPAQUE`, else
/// premultiplied.
#[inline(always)]
#[expect(clippy::cast_possible_truncation, reason = "background and visibility below 2^15")]
fn pixels<const OPAQUE: bool>((acc, vk): ([u16x8; 3], u16x8), bg: [u32; 3]) -> [[u8; 4]; LANES] {
    let [r, g, b] = if OPAQUE {
        let c = |i: usize| add_sat(acc[i], q15k(keep(w(bg[i] as u16)), vk)) >> 7;
        [c(0), c(1), c(2)]
    } else {
        [acc[0] >> 7, acc[1] >> 7, acc[2] >> 7]
    };
    let a = if OPAQUE {
        w(0xff00)
    } else {
        let opacity = keep(w(int::VIS_ONE as u16) - unkeep(vk));
        ((q15k(opacity, keep(w(32640))) + w(64)) >> 7) << 8
    };
    let packed = widen(r | (g << 8)) | (widen(b | a) << 16);
    unpermute(cast::<u32x8, [u32; LANES]>(packed).map(u32::to_le_bytes))
}

/// Whether all 8 tails are empty (every bit zero): such tails add nothing (`T = 1`,
/// `L = 0`), the pixels are their heads' (`docs/layout.md`).
#[inline(always)]
pub(in crate::lanes) fn tails_empty<T: TailFormat>(tails: &[T; LANES]) -> bool {
    cast::<[T; LANES], [u64; LANES]>(*tails).iter().fold(0, |a, &t| a | t) == 0
}

/// The integer RGBA8 resolve of 8 HT pixels (head layers, tails), over the opaque background
/// `bg` (`int::background_channel` values) when `OPAQUE`, else premultiplied; the head alone
/// where every tail is empty.
#[inline(always)]
pub(in crate::lanes) fn resolve<T: TailFormat, const K: usize, const OPAQUE: bool>(
    head: &[[Row; LANES]; K],
    tails: &[T; LANES],
    bg: [u32; 3],
) -> [[u8; 4]; LANES] {
    let head = head_lanes(head);
    if tails_empty(tails) {
        return pixels::<OPAQUE>(head, bg);
    }
    let (sums, alpha, count) = tail_fields(tails);
    let (_, g, t16) = tail_parts(alpha, count);
    pixels::<OPAQUE>(add_tail(head, sums, (g, t16)), bg)
}

/// [`resolve`] of 8 HT pixels whose tails are all empty ([`tails_empty`]): their heads'.
#[inline(always)]
pub(in crate::lanes) fn resolve_head<const K: usize, const OPAQUE: bool>(
    head: &[[Row; LANES]; K],
    bg: [u32; 3],
) -> [[u8; 4]; LANES] {
    pixels::<OPAQUE>(head_lanes(head), bg)
}

/// [`tail_parts`] of `$n` spans' tails at once (`$mid`: their dependency chains overlap; four
/// spans are two 256-bit chains with AVX2), and [`resolve`] of `$n` spans with it, with its
/// background's forms (`$rgba8`, as `super::hybrid_resolve_parts_rgba8`). Written out per
/// span: `array::map` and `from_fn` here were calls, with copies, not inlined.
macro_rules! resolve_spans {
    ($parts:ident, $resolve:ident, $rgba8:ident, $mid:ident, $w:ty, $n:literal: $($i:literal)*) => {
        #[inline(always)]
        fn $parts(alpha: [u32x8; $n], count: [u32x8; $n]) -> [(u32x8, u32x8, u16x8); $n] {
            let inputs = [$(tail_inputs(alpha[$i], count[$i])),*];
            let join = |j: usize| cast::<[u16x8; $n], $w>([$(inputs[$i].0[j]),*]);
            let m = $mid([join(0), join(1), join(2), join(3)]);
            let split = |j: usize| cast::<$w, [u16x8; $n]>(m[j]);
            let m = [split(0), split(1), split(2), split(3), split(4), split(5)];
            [$(tail_end([m[0][$i], m[1][$i], m[2][$i], m[3][$i], m[4][$i], m[5][$i]], inputs[$i].1)),*]
        }

        #[inline(always)]
        pub(in crate::lanes) fn $resolve<T: TailFormat, const K: usize, const OPAQUE: bool>(
            spans: [(&[[Row; LANES]; K], &[T; LANES]); $n],
            bg: [u32; 3],
        ) -> [[[u8; 4]; LANES]; $n] {
            let fields = [$(tail_fields(spans[$i].1)),*];
            let tails = $parts([$(fields[$i].1),*], [$(fields[$i].2),*]);
            [$(pixels::<OPAQUE>(add_tail(head_lanes(spans[$i].0), fields[$i].0, (tails[$i].1, tails[$i].2)), bg)),*]
        }

        #[inline(always)]
        pub(crate) fn $rgba8<T: TailFormat, const K: usize>(
            spans: [(&[[Row; LANES]; K], &[T; LANES]); $n],
            background: IntBackground,
        ) -> [[[u8; 4]; LANES]; $n] {
            by_background!(background, |O, bg| $resolve::<T, K, O>(spans, bg))
        }
    };
}

resolve_spans!(tail_parts2, resolve2, hybrid_resolve_parts2_rgba8, tail_mid16, u16x16, 2: 0 1);
resolve_spans!(tail_parts4, resolve4, hybrid_resolve_parts4_rgba8, tail_mid32, u16x32, 4: 0 1 2 3);

#[cfg(test)]
#[expect(
    clippy::cast_possible_truncation,
    reason = "test bytes and lane indices cut from wider integers on purpose"
)]
mod tests {
    use super::*;

    #[test]
    fn exact_div_is_the_integer_division() {
        // Divisors 1..2^16 against numerators at and around multiples, and the largest ones.
        let mut x = 0x1234_5678u32;
        for b in 1..=65535u32 {
            x ^= x << 13;
            x ^= x >> 17;
            x ^= x << 5;
            let q = x % ((1 << 24) / b);
            let a: [u32; 8] = [
                q * b,
                (q * b).saturating_sub(1),
                q * b + b - 1,
                (1 << 24) - 1,
                x & 0xff_ffff,
                b - 1,
                0,
                (q * b + 1).min((1 << 24) - 1),
            ];
            let got = exact_div(u32x8::new(a), k(b)).to_array();
            assert_eq!(got, a.map(|a| a / b), "b = {b}: {a:?}");
        }
    }

    #[test]
    fn tail_lanes_match_scalar() {
        let mut x = 0x9e37_79b9u32;
        let mut next = || {
            x ^= x << 13;
            x ^= x >> 17;
            x ^= x << 5;
            x
        };
        for i in 0..20_000u32 {
            let a: [u32; 8] = core::array::from_fn(|l| match (i + l as u32) % 4 {
                0 => next() & 0xffff,
                1 => next() & 0x3fff,
                2 => next() % 1200,
                _ => next() % 64,
            });
            let n: [u32; 8] = core::array::from_fn(|l| match (i + 2 * l as u32) % 5 {
                0 => next() & 0xffff,
                1 => next() & 0x7ff,
                2 => next() % 70,
                3 => 0,
                _ => 1 + next() % 8,
            });
            let (t, g) = tail(u32x8::new(a), u32x8::new(n));
            let (t, g) = (t.to_array(), g.to_array());
            for l in 0..8 {
                assert_eq!((t[l], g[l]), int::tail(a[l], n[l]), "S_a = {}, n = {}", a[l], n[l]);
            }
        }
    }

    /// Every alpha sum against counts on both sides of every route's limits (route A's
    /// `u = 12` and `u < 1/2`, route B's `n = 64`, `e_r = 65537` where `u` is a multiple of
    /// 1/2, `T = 1` in the empty tail).
    #[test]
    fn tail_lanes_match_scalar_every_alpha() {
        const COUNTS: [u32; 16] = [0, 1, 2, 3, 5, 8, 13, 21, 34, 55, 63, 64, 65, 144, 2047, 65535];
        for (i, n) in COUNTS.into_iter().enumerate() {
            for a0 in (0..65536u32).step_by(LANES) {
                let a: [u32; 8] = core::array::from_fn(|l| a0 + l as u32);
                let (t, g) = tail(u32x8::new(a), k(n));
                let (t, g) = (t.to_array(), g.to_array());
                for l in 0..8 {
                    assert_eq!((t[l], g[l]), int::tail(a[l], n), "S_a = {}, n = {n}", a[l]);
                }
                // Two spans at once, the second with the alpha sums reversed and another count.
                let (b, m) = (a.map(|a| 65535 - a), COUNTS[(i + 1) % COUNTS.len()]);
                let pair = tail_parts2([u32x8::new(a), u32x8::new(b)], [k(n), k(m)]);
                for (((t, g, _), a), n) in pair.into_iter().zip([a, b]).zip([n, m]) {
                    let (t, g) = (t.to_array(), g.to_array());
                    for l in 0..8 {
                        assert_eq!((t[l], g[l]), int::tail(a[l], n), "pair: S_a = {}, n = {n}", a[l]);
                    }
                }
                // Four: the same two, then with the counts swapped.
                let four = tail_parts4([a, b, a, b].map(u32x8::new), [k(n), k(m), k(m), k(n)]);
                for (((t, g, _), a), n) in four.into_iter().zip([a, b, a, b]).zip([n, m, m, n]) {
                    let (t, g) = (t.to_array(), g.to_array());
                    for l in 0..8 {
                        assert_eq!((t[l], g[l]), int::tail(a[l], n), "four: S_a = {}, n = {n}", a[l]);
                    }
                }
            }
        }
    }

    /// 8 HT pixels of random heads (arbitrary, empty, opaque, fragment-like rows) and
    /// random or adversarial tails, lanes against the scalar definition, both backgrounds.
    fn check_pixels<T: TailFormat>(seed: u64) {
        use crate::Background;
        use glam::Vec3;
        let mut s = seed;
        let mut next = || {
            s = s.wrapping_add(0x9e37_79b9_7f4a_7c15);
            let mut z = s;
            z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
            z ^ (z >> 31)
        };
        let bgs = [
            Background::Transparent,
            Background::Opaque(Vec3::new(0.2, 0.5, 1.0)),
            Background::Opaque(Vec3::ONE),
        ];
        // The three spans before this one (oldest first), once there are three.
        let mut previous = [([[Row::EMPTY; LANES]; 3], [T::EMPTY; LANES]); 3];
        for seen in 0..300 {
            let head: [[Row; LANES]; 3] = core::array::from_fn(|_| {
                core::array::from_fn(|_| {
                    let x = next();
                    match x >> 61 {
                        0 => Row::EMPTY,
                        1 => Row::new([x as u8, (x >> 8) as u8, (x >> 16) as u8], 0, 1.0),
                        _ => Row::from_bytes(x.to_le_bytes()),
                    }
                })
            });
            let tails: [T; LANES] = core::array::from_fn(|_| {
                let x = next();
                match x >> 61 {
                    0 => T::EMPTY,
                    1 => T::from_sums([T::COLOR_MAX; 3], T::ALPHA_MAX, T::COUNT_MAX),
                    2 => T::from_sums([x as u32 & 0xff; 3], (x >> 8) as u32 & 0x3ff, (x >> 20) as u32 % 70),
                    3 => T::from_sums([(x >> 40) as u32 & 0x1fff; 3], 0, (x >> 20) as u32 & 0xf),
                    _ => T::from_bytes(x.to_le_bytes()),
                }
            });
            for bg in bgs {
                let got = match int::background(bg) {
                    Some(b) => resolve::<T, 3, true>(&head, &tails, b),
                    None => resolve::<T, 3, false>(&head, &tails, [0; 3]),
                };
                for l in 0..LANES {
                    let rows = [head[0][l], head[1][l], head[2][l]];
                    assert_eq!(
                        got[l],
                        int::ht_rgba8(&rows, tails[l], bg),
                        "{rows:?} {:?} {bg:?}",
                        tails[l]
                    );
                }
                // Two and four spans at once: each span's bytes as alone.
                let alone = |(h, t): &([[Row; LANES]; 3], [T; LANES])| match int::background(bg) {
                    Some(b) => resolve::<T, 3, true>(h, t, b),
                    None => resolve::<T, 3, false>(h, t, [0; 3]),
                };
                let [(h1, t1), (h2, t2), (h3, t3)] = &previous;
                if seen >= 3 {
                    let spans = [(h3, t3), (&head, &tails)];
                    let pair = match int::background(bg) {
                        Some(b) => resolve2::<T, 3, true>(spans, b),
                        None => resolve2::<T, 3, false>(spans, [0; 3]),
                    };
                    assert_eq!(pair, [alone(&previous[2]), got]);
                    let spans = [(h1, t1), (h2, t2), (h3, t3), (&head, &tails)];
                    let four = match int::background(bg) {
                        Some(b) => resolve4::<T, 3, true>(spans, b),
                        None => resolve4::<T, 3, false>(spans, [0; 3]),
                    };
                    assert_eq!(four, [alone(&previous[0]), alone(&previous[1]), pair[0], got]);
                }
            }
            previous = [previous[1], previous[2], (head, tails)];
        }
    }

    #[test]
    fn pixels_lanes_match_scalar() {
        check_pixels::<crate::Tail>(22);
        check_pixels::<crate::hybrid::PaperTail>(23);
    }
}
