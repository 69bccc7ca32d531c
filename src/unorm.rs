//! Exact unorm8 arithmetic shared by every path (scalar, lanes, and any GPU port).
//!
//! A unorm8 byte `b` stands for the value `b / 255`. The product of two such values is
//! `a * b / 255` bytes, which the kernel rounds to nearest with ties away from zero
//! (ties cannot occur: `a * b / 255` is never exactly `k + 0.5` because 255 is odd, so
//! "round half up" and "round half to even" agree). The quotient is computed without a
//! division by the classic identity, exact for every `x` in `0..=255 * 255`:
//!
//! ```text
//! div255(x) = (x + 128 + ((x + 128) >> 8)) >> 8  ==  round(x / 255)
//! ```
//!
//! Integer arithmetic makes the merge of Listing 1 identical on every machine, in every
//! lane width and in a shader; f32 arithmetic would depend on FMA contraction and on the
//! rounding of the shader compiler.

/// `round(x / 255)` for `x` in `0..=65025` (the product of two bytes).
///
/// Exact on that range; the test `div255_is_exact` checks every value.
#[inline(always)]
pub(crate) const fn div255(x: u32) -> u32 {
    let y = x + 128;
    (y + (y >> 8)) >> 8
}

/// The unorm8 product `round(a * b / 255)`: multiplies two values in `[0, 1]` stored as bytes.
///
/// `mul(a, 255) == a` and `mul(a, 0) == 0` for every `a`, so merging a row with the empty
/// row (or with an opaque one) is exact.
#[inline(always)]
#[expect(clippy::cast_possible_truncation, reason = "round(a * b / 255) <= 255 for bytes")]
pub(crate) const fn mul(a: u8, b: u8) -> u8 {
    // The result is at most 255: no truncation.
    div255(a as u32 * b as u32) as u8
}

/// `floor(y / 255)` for `y` in `0..=65279` (a product of two bytes plus a dither of at most
/// 254): `((y + 1) * 257) >> 16`, one add and one high multiply in 16-bit lanes.
///
/// Exact on that range (`y = 255 q + r` gives `(y + 1) * 257 = 65536 q + 257 (r + 1) - q`
/// with `0 < 257 (r + 1) - q < 65536` for `q <= 255`); `div255_floor_is_exact` checks every value.
/// The lanes compute it in 16-bit slots (`src/lanes/swar.rs`); the scalar merge computes the same value
/// as `(z + (z >> 8)) >> 8` with `z = y + 1` ([`crate::arith`]). Tests use this form as the
/// reference.
#[cfg(test)]
pub(crate) const fn div255_floor(y: u32) -> u32 {
    ((y + 1) * 257) >> 16
}

/// Quantize `v` in `[0, 1]` to a byte: `floor(v * 255 + 0.5)` in f32 (round half up).
///
/// The multiply and the add are two separately rounded f32 operations (Rust never
/// contracts them into an FMA). Out-of-range and NaN inputs saturate (`as` casts from
/// float saturate and map NaN to 0), but validated fragments never produce them.
#[inline(always)]
#[expect(
    clippy::cast_possible_truncation,
    clippy::cast_sign_loss,
    reason = "v in [0, 1]: v * 255 + 0.5 in [0.5, 255.5], truncated as specified"
)]
pub(crate) fn quantize(v: f32) -> u8 {
    (v * 255.0 + 0.5) as u8
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn div255_is_exact() {
        for x in 0..=255u32 * 255 {
            // round(x / 255) with ties up, in exact integer arithmetic.
            let expected = (2 * x + 255) / 510;
            assert_eq!(div255(x), expected, "x = {x}");
        }
    }

    #[test]
    fn div255_floor_is_exact() {
        for y in 0..=255u32 * 255 + 254 {
            assert_eq!(div255_floor(y), y / 255, "y = {y}");
        }
    }

    #[test]
    fn mul_identities() {
        for a in 0..=255u8 {
            assert_eq!(mul(a, 255), a);
            assert_eq!(mul(255, a), a);
            assert_eq!(mul(a, 0), 0);
        }
    }

    #[test]
    fn quantize_rounds_half_up_and_hits_every_byte() {
        for b in 0..=255u8 {
            assert_eq!(quantize(b as f32 / 255.0), b);
        }
        assert_eq!(quantize(0.0), 0);
        assert_eq!(quantize(1.0), 255);
        // 0.5 / 255 is the rounding threshold between 0 and 1.
        assert_eq!(quantize(0.49 / 255.0), 0);
        assert_eq!(quantize(0.51 / 255.0), 1);
    }
}
