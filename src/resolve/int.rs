//! The integer RGBA8 resolve (`docs/layout.md`, "Integer resolve"): what
//! [`Framebuffer::resolve_rgba8`](crate::Framebuffer::resolve_rgba8) writes for MLAB. Every
//! value is an unsigned integer below `2^31`; the one product is [`q15`]; the same bytes in
//! scalar code, in every `wide` backend (`src/lanes/resolve_int/`, 16-bit lanes) and in a shader.

use super::Background;

/// Visibility 1 (Q15): the visibility `V` of the layers in front is held as
/// `v ~ 32767 V`.
pub(crate) const VIS_ONE: u32 = 32767;
/// A color accumulator starts at half an output step (1/128 byte), so that the final
/// `>> 7` rounds to nearest.
pub(crate) const ACC_START: u32 = 64;
/// Largest accumulator value (the 16-bit lanes add with signed saturation): `255.99`
/// bytes, above every value that rounds to 255.
pub(crate) const ACC_MAX: u32 = 32767;
/// A background channel `b` in `[0, 1]` enters as `round(b * 32640)` (`32640 = 255 * 128`,
/// the accumulator's unit).
pub(crate) const BG_SCALE: f32 = 32640.0;

/// `(x * y + 16384) >> 15` for `x, y` in `0..=32767`: the rounded Q15 product (x86
/// `pmulhrsw`, NEON `sqrdmulh`, wasm `q15mulr_sat` agree on these operands). Below 2^30.
#[inline(always)]
pub(crate) const fn q15(x: u32, y: u32) -> u32 {
    (x * y + 16384) >> 15
}

/// A row byte's factor: color `c` as `128 c`, transmittance `t` as `floor(257 t / 2)`
/// (`~ 32768 t / 255`; 32767 for `t = 255`).
#[inline(always)]
pub(crate) const fn t_factor(t: u32) -> u32 {
    (t * 257) >> 1
}

/// One background channel: clamped to `[0, 1]` as [`crate::to_rgba8`] clamps (NaN to
/// 0), then `floor(b * 32640 + 0.5)` in f32 (a multiply, then an add).
#[inline]
#[expect(
    clippy::cast_possible_truncation,
    clippy::cast_sign_loss,
    reason = "b in [0, 1]: b * 32640 + 0.5 in [0.5, 32640.5], truncated as specified"
)]
pub(crate) fn background_channel(b: f32) -> u32 {
    let b = if b > 1.0 { 1.0 } else { b };
    let b = if b >= 0.0 { b } else { 0.0 };
    (b * BG_SCALE + 0.5) as u32
}

/// A background as the integer resolve takes it: its three channels
/// ([`background_channel`]), or `None` for [`Background::Transparent`]; computed once
/// per resolve call, outside the loops over lines and spans.
pub(crate) type IntBackground = Option<[u32; 3]>;

/// The background's three channels, or `None` for [`Background::Transparent`].
#[inline]
pub(crate) fn background(bg: Background) -> Option<[u32; 3]> {
    match bg {
        Background::Opaque(c) => Some(c.to_array().map(background_channel)),
        Background::Transparent => None,
    }
}

/// Eq. 5 in integers over rows given as `[R, G, B, T]` bytes, front to back, every row
/// visited: per row `acc_c = min(32767, acc_c + q15(128 c, v))` for each channel, then
/// `v = q15(floor(257 t / 2), v)`. Returns the three accumulators and `v`.
#[inline(always)]
pub(crate) fn layers(rows: impl Iterator<Item = [u8; 4]>) -> ([u32; 3], u32) {
    let mut acc = [ACC_START; 3];
    let mut v = VIS_ONE;
    for [r, g, b, t] in rows {
        for (a, c) in acc.iter_mut().zip([r, g, b]) {
            *a = (*a + q15(128 * c as u32, v)).min(ACC_MAX);
        }
        v = q15(t_factor(t as u32), v);
    }
    (acc, v)
}

/// The pixel from the accumulators and the visibility: over an opaque background
/// `min(32767, acc_c + q15(bg_c, v)) >> 7` and alpha 255; premultiplied (transparent)
/// `acc_c >> 7` and alpha `(q15(32767 - v, 32640) + 64) >> 7`.
#[inline(always)]
#[expect(clippy::cast_possible_truncation, reason = "every value is at most 32767 >> 7 = 255")]
pub(crate) fn pixel(acc: [u32; 3], v: u32, bg: Option<[u32; 3]>) -> [u8; 4] {
    match bg {
        Some(bg) => {
            let c: [u32; 3] = core::array::from_fn(|i| (acc[i] + q15(bg[i], v)).min(ACC_MAX) >> 7);
            [c[0] as u8, c[1] as u8, c[2] as u8, 255]
        }
        None => {
            let a = (q15(VIS_ONE - v, 32640) + 64) >> 7;
            [(acc[0] >> 7) as u8, (acc[1] >> 7) as u8, (acc[2] >> 7) as u8, a as u8]
        }
    }
}

/// The integer RGBA8 resolve of one pixel's rows.
#[inline]
pub(crate) fn rgba8(rows: &[crate::Row], bg: Background) -> [u8; 4] {
    let (acc, v) = layers(rows.iter().map(|r| r.rgbt()));
    pixel(acc, v, background(bg))
}

/// `round(2^24 / (255 (k + 1)))`: `h(m) = sum_k m^k / (k + 1)` in units of `1 / 65793`
/// (`2^24 / 255 = 65793.004`), so that `S_a * h` is the optical depth `u` in `2^-24`.
pub(crate) const H: [u32; 8] = [65793, 32897, 21931, 16448, 13159, 10966, 9399, 8224];
/// `round(65536 e^(-1/2) / k!)`: `e^(-r) = e^(-1/2) e^(1/2 - r)` on `r` in `[0, 1/2)`.
pub(crate) const EXP: [u32; 7] = [39750, 39750, 19875, 6625, 1656, 331, 55];
/// `round(65536 e^(-2^i / 2))`: the factor of bit `i` of `floor(2 u)`.
pub(crate) const EXP_BITS: [u32; 6] = [39750, 24109, 8869, 1200, 22, 0];
/// `round(65536 / (k + 1)!)`: `psi(u) = (e^u - 1) / u`.
pub(crate) const PSI: [u32; 6] = [65536, 32768, 10923, 2731, 546, 91];
/// 1 in the tail's Q16 values (`T`, `g`).
pub(crate) const Q16_ONE: u32 = 65536;

/// `(x * y + 32768) >> 16`, the rounded Q16 product (the operands keep it below 2^32).
#[cfg_attr(
    not(test),
    allow(dead_code, reason = "the scalar definition, against which the tests check the lanes")
)]
#[inline(always)]
const fn q16(x: u32, y: u32) -> u32 {
    (x * y + 32768) >> 16
}

/// The HT tail's transmittance and color factor, from its alpha sum (at most 65535) and
/// count (at most 65535), in Q16 (`65536` = 1): `(T, g)` with `T ~ (1 - m)^n`,
/// `g ~ (1 - T) / (n m)`, `m = S_a / (255 n)` (`docs/layout.md`, "Integer resolve of HT").
/// A zero count is a count of 1; a mean alpha of 1 or more gives `T = 0`, `g = 255 / S_a`.
#[cfg_attr(
    not(test),
    allow(dead_code, reason = "the scalar definition, against which the tests check the lanes")
)]
#[inline(always)]
pub(crate) fn tail(alpha: u32, count: u32) -> (u32, u32) {
    let n = if count == 0 { 1 } else { count };
    // m ~ 65536 S_a / (255 n): 257 S_a < 2^24, an exact integer division.
    let m = (257 * alpha) / n;
    let series = m <= 16384; // m <= 1/4: u = s h(m); else T = x^n directly
    let mm = if m < 16384 { m } else { 16384 };
    let mut h = H[7];
    for k in (0..7).rev() {
        h = H[k] + q16(h, mm);
    }
    let sa = if alpha < 4095 { alpha } else { 4095 };
    let u = (sa * h + 128) >> 8; // u = (S_a / 255) h(m) in Q16 (u >= 16 for S_a >= 4095)
    let j = u >> 15; // floor(2 u)
    let y = 32768 - (u & 32767); // 1/2 - (u - j / 2), in (0, 1/2]
    let mut e_r = EXP[6];
    for k in (0..6).rev() {
        e_r = EXP[k] + q16(e_r, y);
    }
    let x = 65535 - if m < 65535 { m } else { 65535 }; // 1 - m
    let zero = if series { u >= 786_432 } else { n >= 64 }; // u >= 12; (3/4)^64
    let bits = if zero {
        0
    } else if series {
        j
    } else {
        n
    };
    let mut p = if series { e_r } else { Q16_ONE };
    let mut b = x;
    for (i, e_bit) in EXP_BITS.into_iter().enumerate() {
        // Route A multiplies by e^(-2^i / 2), route B by x^(2^i), for each set bit.
        if (bits >> i) & 1 != 0 {
            p = q16(p, if series { e_bit } else { b });
        }
        b = q16(b, b);
    }
    let t = if zero {
        0
    } else if p < Q16_ONE {
        p
    } else {
        Q16_ONE
    };
    // g = h(m) phi(u), phi(u) = e^(-u) psi(u), for u < 1/2 (route A); else (1 - T) / s.
    let uu = if u < 32767 { u } else { 32767 };
    let mut psi = PSI[5];
    for k in (0..5).rev() {
        psi = PSI[k] + q16(psi, uu);
    }
    let phi = ((t >> 1) * psi + 16384) >> 15;
    let g_series = phi + (((((h - H[0]) * phi + 128) >> 8) * 255 + 32768) >> 16);
    let g_div = ((Q16_ONE - t) * 255) / if alpha == 0 { 1 } else { alpha };
    let g = if series && u < 32768 { g_series } else { g_div };
    (t, if g < Q16_ONE { g } else { Q16_ONE })
}

/// Head then tail in integers: `acc_c += (L_c >> 15) v + q15(L_c & 32767, v)` with
/// `L_c = (S_c g + 256) >> 9` the tail's light in accumulator units (`128 * 255 C_tail`,
/// up to 20 bits), then `v = (T v + 32768) >> 16`.
#[cfg_attr(
    not(test),
    allow(dead_code, reason = "the scalar definition, against which the tests check the lanes")
)]
#[inline(always)]
pub(crate) fn with_tail(acc: [u32; 3], v: u32, sums: [u32; 3], alpha: u32, count: u32) -> ([u32; 3], u32) {
    let (t, g) = tail(alpha, count);
    let acc = core::array::from_fn(|i| {
        let l = (sums[i] * g + 256) >> 9;
        let a = acc[i] + (l >> 15) * v + q15(l & 32767, v);
        if a < ACC_MAX { a } else { ACC_MAX }
    });
    (acc, q16(t, v))
}

/// The integer RGBA8 resolve of one HT pixel: the head rows, then the tail's fields.
#[cfg_attr(
    not(test),
    allow(dead_code, reason = "the scalar definition, against which the tests check the lanes")
)]
#[inline]
pub(crate) fn ht_rgba8<T: crate::TailFormat>(head: &[crate::Row], tail: T, bg: Background) -> [u8; 4] {
    let (acc, v) = layers(head.iter().map(|r| r.rgbt()));
    let (acc, v) = with_tail(acc, v, tail.color_sum(), tail.alpha_sum(), tail.count());
    pixel(acc, v, background(bg))
}
