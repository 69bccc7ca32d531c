//! The integer RGBA8 resolve of HT heads and tails (`crate::resolve::int::ht_rgba8`,
//! `docs/layout.md`, "Integer resolve of HT") for 8 pixels: one pixel per 32-bit lane, in
//! the lane order of `src/lanes/x8.rs` (`POSITION`), every step the scalar definition's, so
//! the bytes are the scalar's. The two exact integer divisions are computed as f32 divisions
//! (both operands below 2^24, the divisor at least 1: the truncated correctly rounded quotient
//! is the integer quotient; `exact_div_is_the_integer_division` tests it).

use super::LANES;
use super::x8::{layer_words, tail_fields, unpermute};
use crate::resolve::int;
use crate::row::Row;
use crate::tail::TailFormat;
use bytemuck::cast;
use wide::{f32x8, i16x8, i16x16, i32x8, u16x8, u32x8};

// Every product below is a 16-bit one (issue 31: `wide` has no 32-bit lane multiply or
// unsigned 32-bit min on SSE2, and emulated them at 228 instructions per pixel): `pmaddwd`
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



/// `(x * y + 32768) >> 16` per 16-bit lane for `x, y` in `0..=65535`: the high half of the
/// product plus bit 15 of its low half (`pmulhuw`, `pmullw`).
#[inline(always)]
fn q16w(x: u16x8, y: u16x8) -> u16x8 {
    x.mul_keep_high(y) + ((x * y) >> 15)
}

/// `sum_k c[k] y^k - c[0]` per 16-bit lane as the rounded Horner sum of `int` computes it
/// (`x = c[n - 1]`, then `x = c[k] + q16(x, y)` down to `k = 1`, then `q16(x, y)`), from
/// `y2 = 2 y` (at most 65535): `q16(x, y) = (mulhi(x, 2 y) + 1) >> 1` (`mulhi(x, 2y)` is
/// `floor(x y / 2^15)`), and for `k >= 2` the coefficient folds in as `(mulhi + 2 c + 1) >> 1`,
/// below 2^16 for every operand of `int::{H, EXP, PSI}` (largest 54164, `h` at `k = 2`): one
/// multiply, one add and one shift per step.
#[inline(always)]
#[expect(clippy::cast_possible_truncation, reason = "coefficients below 2^15 at k >= 2, below 2^16 at k = 1")]
fn horner_tail(c: &[u32], y2: u16x8) -> u16x8 {
    let n = c.len();
    let mut x = w(c[n - 1] as u16);
    for &ck in c[2..n - 1].iter().rev() {
        x = (x.mul_keep_high(y2) + w((2 * ck + 1) as u16)) >> 1;
    }
    x = ((x.mul_keep_high(y2) + w(1)) >> 1) + w(c[1] as u16);
    (x.mul_keep_high(y2) + w(1)) >> 1
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

/// `a > b` per 16-bit lane, both in `0..=32767`.
#[inline(always)]
fn gt(a: u16x8, b: u16x8) -> u16x8 {
    cast::<i16x8, u16x8>(cast::<u16x8, i16x8>(a).simd_gt(cast::<u16x8, i16x8>(b)))
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
pub(super) fn exact_div(a: u32x8, b: u32x8) -> u32x8 {
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
pub(super) fn tail(alpha: u32x8, count: u32x8) -> (u32x8, u32x8) {
    let (t, g, _) = tail_parts(alpha, count);
    (t, g)
}

/// `int::tail` per lane: `T`, `g`, and `min(T, 65535)` in 16-bit lanes.
#[inline(always)]
#[expect(
    clippy::cast_possible_truncation,
    reason = "the constants of `int` are below 2^16 where they are cut to 16-bit lanes"
)]
fn tail_parts(alpha: u32x8, count: u32x8) -> (u32x8, u32x8, u16x8) {
    let one = f32x8::ONE;
    let alpha_f = f32x8::from_i32x8(cast(alpha));
    // m = (257 S_a) / max(count, 1), both below 2^24.
    let m = div_f32(
        f32x8::from_i32x8(cast((alpha << 8) + alpha)),
        f32x8::from_i32x8(cast(count)).fast_max(one),
    );
    let ms = narrow(m); // min(m, 32767)
    let route_b = gt(ms, w(16384)); // !series
    let mm = min15(ms, w(16384));
    // 65535 - min(m, 65535): `packssdw` of m - 32768 is min(m, 65535) - 32768 (m >= 0).
    let x = narrow(m - k(32768)) ^ w(0x7fff);
    let n = cast::<i16x8, u16x8>(cast::<u16x8, i16x8>(narrow(count)).max(i16x8::splat(1))); // min(n, 32767)
    let sa = min15(narrow(alpha), w(4095));
    // h(m) = H[0] + hd.
    let hd = horner_tail(&int::H, mm << 1);
    // u = (sa (65536 + 257 + hd) + 128) >> 8 = 256 (sa + hi) + ((lo + 128) >> 8), with
    // hi, lo the halves of sa (257 + hd) (below 2^26); then u = 256 s + r', r' < 256.
    let hq = hd + w(257);
    let lo = sa * hq;
    let r = ((lo >> 1) + w(64)) >> 7; // (lo + 128) >> 8, in 0..=256
    let s = sa.mul_keep_high(hq) + sa + (r >> 8);
    let j = s >> 7; // u >> 15
    let ul: u16x8 = ((s & w(127)) << 8) | (r & w(255)); // u & 32767
    let y = w(32768) - ul;
    let uu = ul | (gt(j, w(0)) & w(32767)); // min(u, 32767)
    let ed = ul.simd_eq(w(0)).select(w(ED_HALF), horner_tail(&int::EXP, y << 1)); // e_r - EXP[0], at most 25787
    // zero = series ? u >= 786432 : n >= 64;  bits = zero ? 0 : (series ? j : n).
    let zero = route_b.select(gt(n, w(63)), gt(j, w(23)));
    let bits = route_b.select(n, j) & !zero;
    // p = p_lo + 65536 (hi & 1): e_r (up to 65537) on route A, 1 on route B. After its
    // first product a lane's p is below 2^16: q16(p, f) = q16(p_lo, f) + (hi & f).
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
        b = q16w(b, b);
    }
    // T = zero ? 0 : min(p, 65536): t16 = min(T, 65535), top bit `hi`.
    let hi = hi & !zero;
    let t16 = (p & !zero) | hi;
    let t = widen(t16) + (widen(hi) & k(1));
    let psd = horner_tail(&int::PSI, uu << 1); // psi - 65536, below 2^15
    // phi = ((T >> 1) psi + 16384) >> 15 = 2 th + ((th psd + 16384) >> 15), th = T >> 1.
    let th: u16x8 = (t16 >> 1) + (hi & w(1));
    let c = (th.mul_keep_high(psd) << 1) + ((((th * psd) >> 1) + w(8192)) >> 14);
    let phi = (widen(th) << 1) + widen(c);
    let l = (widen(hd) * phi + k(128)) >> 8;
    let g_series = phi + (((l << 8) - l + k(32768)) >> 16);
    let d = k(int::Q16_ONE) - t;
    let g_div = div_f32(f32x8::from_i32x8(cast((d << 8) - d)), alpha_f.fast_max(one));
    let use_series = widen_mask(!route_b & j.simd_eq(w(0)));
    let g = cast::<i32x8, u32x8>(cast::<u32x8, i32x8>(use_series.select(g_series, g_div)).min(i32x8::splat(65536)));
    (t, g, t16)
}

/// `q15(x, y) = (x y + 16384) >> 15` per 16-bit lane from the doubled factors `x2 = 2 x`,
/// `y2 = 2 y` (both at most 65535): `(mulhi(x2, y2) + 1) >> 1` (`pmulhuw`, `pavgw`; the
/// SSE2 form of the MLAB integer resolve, `docs/layout.md`).
#[inline(always)]
fn q15d(x2: u16x8, y2: u16x8) -> u16x8 {
    (x2.mul_keep_high(y2) + w(1)) >> 1
}

/// The integer RGBA8 resolve of 8 HT pixels (head layers, tails), over the opaque background
/// `bg` (`int::background_channel` values) when `OPAQUE`, else premultiplied. The head runs
/// in 16-bit lanes with doubled factors (`128 c` as `c << 8`, `floor(257 T / 2)` as
/// `257 T & !1`, `v` as `2 v`), 8 pixels in one 128-bit register.
#[inline(always)]
#[expect(clippy::cast_possible_truncation, reason = "accumulator start and background below 2^15")]
pub(super) fn resolve<T: TailFormat, const K: usize, const OPAQUE: bool>(
    head: &[[Row; LANES]; K],
    tails: &[T; LANES],
    bg: [u32; 3],
) -> [[u8; 4]; LANES] {
    let high = w(0xff00);
    let mut acc = [w(int::ACC_START as u16); 3];
    let mut v2 = w(2 * int::VIS_ONE as u16);
    for layer in head {
        let words = cast::<u32x8, i32x8>(layer_words(layer));
        // [R | G << 8] and [B | T << 8] per pixel (`packssdw` of sign-extended halves).
        let rg = cast::<i16x8, u16x8>(i16x8::from_i32x8_truncate(words));
        let bt = cast::<i16x8, u16x8>(i16x8::from_i32x8_saturate(words >> 16));
        for (a, c) in acc.iter_mut().zip([rg << 8, rg & high, bt << 8]) {
            *a = cast::<i16x8, u16x8>(cast::<u16x8, i16x8>(*a).saturating_add(cast(q15d(c, v2))));
        }
        let t = bt >> 8;
        v2 = q15d(((t << 8) + t) & w(0xfffe), v2) << 1;
    }
    let (sums, alpha, count) = tail_fields(tails);
    let (_, g, t16) = tail_parts(alpha, count);
    // S_c g = 4 S_c (g >> 2) + S_c (g & 3) (`pmaddwd`: 4 S_c < 2^15, g <= 65536).
    let gq = (g >> 2) | ((g & k(3)) << 16);
    let v = widen(v2 >> 1);
    let v_hi = v << 16;
    for (a, s) in acc.iter_mut().zip(sums) {
        let l = (mul15((s << 2) | (s << 16), gq) + k(256)) >> 9;
        // l as the 16-bit pair (l & 32767, l >> 15): (l >> 15) v + q15(l & 32767, v),
        // saturated to 32767 by `packssdw`, then added with saturation.
        let pair = l + (l & k(!32767));
        let term = mul15(pair, v_hi) + ((mul15(pair, v) + k(16384)) >> 15);
        *a = cast::<i16x8, u16x8>(cast::<u16x8, i16x8>(*a).saturating_add(cast(narrow(term))));
    }
    // q16(T, v) = q16(min(T, 65535), v) for v <= 32768.
    let v2 = q15d(t16, v2) << 1;
    let [r, g, b] = if OPAQUE {
        let bg = bg.map(|b| w(2 * b as u16));
        core::array::from_fn(|i| cast::<i16x8, u16x8>(cast::<u16x8, i16x8>(acc[i]).saturating_add(cast(q15d(bg[i], v2)))) >> 7)
    } else {
        acc.map(|a| a >> 7)
    };
    let a = if OPAQUE {
        high
    } else {
        let v = v2 >> 1;
        ((q15d((w(int::VIS_ONE as u16) - v) << 1, w(65280)) + w(64)) >> 7) << 8
    };
    let packed = widen(r | (g << 8)) | (widen(b | a) << 16);
    unpermute(cast::<u32x8, [u32; LANES]>(packed).map(u32::to_le_bytes))
}

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
        for n in COUNTS {
            for a0 in (0..65536u32).step_by(LANES) {
                let a: [u32; 8] = core::array::from_fn(|l| a0 + l as u32);
                let (t, g) = tail(u32x8::new(a), k(n));
                let (t, g) = (t.to_array(), g.to_array());
                for l in 0..8 {
                    assert_eq!((t[l], g[l]), int::tail(a[l], n), "S_a = {}, n = {n}", a[l]);
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
        for _ in 0..300 {
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
            }
        }
    }

    #[test]
    fn pixels_lanes_match_scalar() {
        check_pixels::<crate::Tail>(22);
        check_pixels::<crate::hybrid::PaperTail>(23);
    }
}
