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
use wide::{f32x8, i32x8, u32x8};

/// All lanes `v`.
#[inline(always)]
fn k(v: u32) -> u32x8 {
    u32x8::splat(v)
}

/// `(x * y + 32768) >> 16` per lane.
#[inline(always)]
fn q16(x: u32x8, y: u32x8) -> u32x8 {
    (x * y + k(32768)) >> 16
}

/// `(x * y + 16384) >> 15` per lane.
#[inline(always)]
fn q15(x: u32x8, y: u32x8) -> u32x8 {
    (x * y + k(16384)) >> 15
}

/// `floor(a / b)` for `a < 2^24`, `1 <= b < 2^24`: the f32 quotient, correctly rounded and
/// truncated, is the integer quotient (half an ulp of `a / b` is below `1 / b`, the distance
/// from a non-integer quotient to the next integer).
#[inline(always)]
pub(super) fn exact_div(a: u32x8, b: u32x8) -> u32x8 {
    let q = f32x8::from_i32x8(cast(a)) / f32x8::from_i32x8(cast(b));
    cast::<i32x8, u32x8>(q.fast_trunc_int())
}

/// `if mask { a } else { b }` per lane (`mask` all ones or all zeros).
#[inline(always)]
fn sel(mask: u32x8, a: u32x8, b: u32x8) -> u32x8 {
    mask.select(a, b)
}

/// `int::tail` per lane: `(T, g)` in Q16.
#[inline(always)]
pub(super) fn tail(alpha: u32x8, count: u32x8) -> (u32x8, u32x8) {
    let zero_count = count.simd_eq(u32x8::ZERO);
    let n = sel(zero_count, k(1), count);
    let m = exact_div(alpha * k(257), n);
    let series = !m.simd_gt(k(16384));
    let mm = m.min(k(16384));
    let mut h = k(int::H[7]);
    for c in int::H[..7].iter().rev() {
        h = k(*c) + q16(h, mm);
    }
    let u: u32x8 = (alpha.min(k(4095)) * h + k(128)) >> 8;
    let j = u >> 15;
    let y = k(32768) - (u & k(32767));
    let mut e_r = k(int::EXP[6]);
    for c in int::EXP[..6].iter().rev() {
        e_r = k(*c) + q16(e_r, y);
    }
    let x = k(65535) - m.min(k(65535));
    let zero = sel(series, u.simd_gt(k(786_431)), n.simd_gt(k(63)));
    let bits = sel(zero, u32x8::ZERO, sel(series, j, n));
    let mut p = sel(series, e_r, k(int::Q16_ONE));
    let mut b = x;
    // Bits above the largest lane's are zero in every lane: their steps change nothing.
    let top = bits.to_array().iter().fold(0, |a, &v| a | v);
    let steps = (u32::BITS - top.leading_zeros()) as usize;
    for (i, e_bit) in int::EXP_BITS.into_iter().enumerate().take(steps) {
        let on = (bits & k(1 << i)).simd_eq(k(1 << i));
        p = sel(on, q16(p, sel(series, k(e_bit), b)), p);
        b = q16(b, b);
    }
    let t = sel(zero, u32x8::ZERO, p.min(k(int::Q16_ONE)));
    let uu = u.min(k(32767));
    let mut psi = k(int::PSI[5]);
    for c in int::PSI[..5].iter().rev() {
        psi = k(*c) + q16(psi, uu);
    }
    let phi = ((t >> 1) * psi + k(16384)) >> 15;
    let g_series = phi + (((((h - k(int::H[0])) * phi + k(128)) >> 8) * k(255) + k(32768)) >> 16);
    let g_div = exact_div((k(int::Q16_ONE) - t) * k(255), alpha.max(k(1)));
    let use_series = series & !u.simd_gt(k(32767));
    (t, sel(use_series, g_series, g_div).min(k(int::Q16_ONE)))
}

/// The integer RGBA8 resolve of 8 HT pixels (head layers, tails), over the opaque background
/// `bg` (`int::background_channel` values) when `OPAQUE`, else premultiplied.
#[inline(always)]
pub(super) fn resolve<T: TailFormat, const K: usize, const OPAQUE: bool>(
    head: &[[Row; LANES]; K],
    tails: &[T; LANES],
    bg: [u32; 3],
) -> [[u8; 4]; LANES] {
    let byte = k(0xff);
    let mut acc = [k(int::ACC_START); 3];
    let mut v = k(int::VIS_ONE);
    for layer in head {
        let w = layer_words(layer);
        let c = [w & byte, (w >> 8) & byte, (w >> 16) & byte];
        for (a, c) in acc.iter_mut().zip(c) {
            // q15(128 c, v) = (c v + 128) >> 8
            let p: u32x8 = (c * v + k(128)) >> 8;
            *a = (*a + p).min(k(int::ACC_MAX));
        }
        v = q15(((w >> 24) * k(257)) >> 1, v);
    }
    let (sums, alpha, count) = tail_fields(tails);
    let (t, g) = tail(alpha, count);
    let acc: [u32x8; 3] = core::array::from_fn(|i| {
        let l: u32x8 = (sums[i] * g + k(256)) >> 9;
        let hi: u32x8 = l >> 15;
        (acc[i] + hi * v + q15(l & k(32767), v)).min(k(int::ACC_MAX))
    });
    let v = q16(t, v);
    let packed = if OPAQUE {
        let c: [u32x8; 3] = core::array::from_fn(|i| (acc[i] + q15(k(bg[i]), v)).min(k(int::ACC_MAX)) >> 7);
        c[0] | (c[1] << 8) | (c[2] << 16) | k(0xff00_0000)
    } else {
        let a = (q15(k(int::VIS_ONE) - v, k(32640)) + k(64)) >> 7;
        (acc[0] >> 7) | ((acc[1] >> 7) << 8) | ((acc[2] >> 7) << 16) | (a << 24)
    };
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
