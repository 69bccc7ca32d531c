//! The hash of a fragment in a pixel, which seeds [`Unbiased`](crate::Unbiased)'s dithers
//! (`docs/layout.md`): `lowbias32` twice. Used by the fragment, the row inserts and the lanes.

/// The 32-bit integer hash `lowbias32` (Chris Wellons, "Prospecting for Hash Functions",
/// 2018: the constants of his `lowbias32`), a bijection of `u32`:
///
/// ```text
/// x ^= x >> 16;  x *= 0x7feb352d;  x ^= x >> 15;  x *= 0x846ca68b;  x ^= x >> 16
/// ```
///
/// (multiplications modulo 2^32). Used by [`fragment_hash`].
#[inline(always)]
#[must_use]
pub const fn lowbias32(x: u32) -> u32 {
    let x = (x ^ (x >> 16)).wrapping_mul(0x7feb_352d);
    let x = (x ^ (x >> 15)).wrapping_mul(0x846c_a68b);
    x ^ (x >> 16)
}

/// The hash of a fragment in a pixel, which seeds both of [`Unbiased`](crate::Unbiased)'s dithers:
/// `h = lowbias32(key ^ lowbias32(pixel))`.
///
/// `key` is the fragment's stable key ([`Fragment::with_key`](crate::Fragment::with_key): the primitive's id, the same
/// in every frame) or, without one, its content key ([`Fragment::hash`](crate::Fragment::hash)); `pixel` is the
/// pixel's id (`first line's pixel + y * width + x` in a framebuffer, `docs/layout.md`;
/// whatever id the caller picks for a [`BlendingArray`](crate::BlendingArray), such as a
/// pixel or ray index). With a stable key and pixel, the same fragment is rounded the same
/// way in every frame, whatever its depth does: a camera move does not re-roll the dither.
#[inline(always)]
#[must_use]
pub const fn fragment_hash(key: u32, pixel: u32) -> u32 {
    lowbias32(key ^ lowbias32(pixel))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `lowbias32` on values published with it (Wellons' `hash-prospector` README lists
    /// its bias, not values: these were computed from the formula by hand-checked steps) and
    /// its bijectivity on a sample.
    #[test]
    fn lowbias32_is_the_formula() {
        assert_eq!(lowbias32(0), 0);
        let by_steps = |x: u32| {
            let mut x = x;
            x ^= x >> 16;
            x = x.wrapping_mul(0x7feb_352d);
            x ^= x >> 15;
            x = x.wrapping_mul(0x846c_a68b);
            x ^ (x >> 16)
        };
        let mut x = 1u32;
        for _ in 0..10_000 {
            assert_eq!(lowbias32(x), by_steps(x));
            x = x.wrapping_mul(747_796_405).wrapping_add(2_891_336_453);
        }
        assert_eq!(fragment_hash(7, 3), lowbias32(7 ^ lowbias32(3)));
    }
}
