//! The two arithmetics of the kernel: the paper's round-to-nearest ([`Paper`]) and the
//! default, unbiased one ([`Unbiased`]).
//!
//! Every kernel type takes the arithmetic as a type parameter that defaults to
//! [`Unbiased`]: `BlendingArray<4>` is `BlendingArray<4, Unbiased>`, and
//! `BlendingArray<4, Paper>` is the paper's arithmetic bit for bit. The arithmetic decides
//! three things, nothing else (the row layout, Listing 1's sort, Listing 2's head and the
//! resolve are the same):
//!
//! | | [`Paper`] | [`Unbiased`] (default) |
//! |---|---|---|
//! | merge products (Eq. 7-8) | `round(a * b / 255)` | `floor((a * b + d) / 255)`, `d` = the merge dither in `0..=254` (`docs/layout.md`) |
//! | fragment quantization | `floor(v * 255 + 0.5)` | the same, except faint fragments (`alpha * 255 < 16`): `floor(v * 255 + u)`, `u` = the fragment dither (`docs/layout.md`) |
//! | HT tail | [`PaperTail`]: colors 3 x 10 bit, alpha 16, count 16 | [`Tail`]: colors 3 x 13 bit, alpha 14, count 11 |
//!
//! # Why
//!
//! Rounding a unorm8 product to nearest is exact on average for one product, but a chain of
//! merges of faint layers stalls: `round(T * (255 - a) / 255) == T` as soon as
//! `a * T < 127.5`, so the transmittance of a pixel crossed by many fragments of alpha
//! `1/255` never falls below `127/255` (exact: it tends to 0), and a fog of 1000 such
//! fragments keeps half of the background visible. [`Unbiased`] rounds down or up with
//! probability equal to the fraction: for a dither `d` uniform on `0..=254`,
//! `E[floor((p + d) / 255)] = p / 255` exactly, so the stored transmittance is an unbiased
//! estimate of the exact product and does not stall. The dither is a hash of the two rows'
//! bits (no state, no randomness source): the same rows give the same bytes on every
//! machine, every SIMD backend and in a shader with 32-bit integers.
//!
//! Exactness is kept where the paper is exact (tested): merging with the empty row is the
//! identity (`floor((255 * t + d) / 255) = t` for `d <= 254`), an opaque row stays opaque,
//! opaque fragments converge to a z-buffer, an array with `M >= n` rows holds every fragment
//! exactly as quantized. The colors use the complementary dither `254 - d`, which keeps
//! `color <= 255 - T` an invariant of the merge, as it is for the paper's rounding.
//!
//! What the dither cannot do: when the same two rows are merged again and again (the same
//! fragment, same depth, same color, submitted many times into a pixel whose last row does
//! not change), the hash is the same each time and the merge is a fixed point, as with the
//! paper's rounding. Any change of depth or color between the fragments moves it.
//!
//! [`PaperTail`]: crate::hybrid::PaperTail
//! [`Tail`]: crate::hybrid::Tail

use core::hint::select_unpredictable;

use crate::fragment::Fragment;
use crate::row::Row;
use crate::tail::{PaperTail, Tail, TailFormat};
use crate::unorm::mul;

/// Which arithmetic, for code that is written once for both (crate-internal).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Kind {
    /// Round to nearest, paper tail.
    Paper,
    /// Dithered rounding, wide tail.
    Unbiased,
}

impl crate::sealed::Sealed for Paper {}
impl crate::sealed::Sealed for Unbiased {}

/// The arithmetic of the merge, of fragment quantization and of the HT tail: [`Paper`] or
/// [`Unbiased`] (see the [module docs](self)). Sealed: the kernel's lane code implements
/// exactly these two.
pub trait Arithmetic:
    crate::sealed::Sealed + Copy + Default + PartialEq + Eq + core::hash::Hash + core::fmt::Debug + Send + Sync + 'static
{
    /// Which one (used by the lane code to pick its instructions).
    // The type is the crate's own: the trait is sealed, no other crate implements or reads it.
    #[allow(private_interfaces)]
    #[doc(hidden)]
    const KIND: Kind;
    /// `"paper"` or `"unbiased"`.
    const NAME: &'static str = match Self::KIND {
        Kind::Paper => "paper",
        Kind::Unbiased => "unbiased",
    };
    /// The HT tail of this arithmetic.
    type Tail: TailFormat;

    /// Merge two neighbouring rows (Eq. 7-8), `front` nearer: see [`crate::mlab::insert_with`] and the [module docs](self).
    fn merge(front: Row, back: Row) -> Row;

    /// Quantize a validated fragment into a row.
    fn quantize(fragment: &Fragment) -> Row;

    /// The last step of Listing 1 on one pixel: `merge(a, b)` if `a_first`, else
    /// `merge(b, a)`. The same bytes as selecting then merging; [`Unbiased`] hashes its
    /// dither from the pair before the choice (the hash is symmetric), which takes the hash
    /// off the insert's dependency chain.
    #[doc(hidden)]
    #[inline(always)]
    fn merge_pair(a_first: bool, a: Row, b: Row) -> Row {
        // Branchless, as Listing 1's swaps: the depth order of an unsorted stream is random.
        let (front, back) = (select_unpredictable(a_first, a, b), select_unpredictable(a_first, b, a));
        Self::merge(front, back)
    }
}

/// The paper's arithmetic: products rounded to nearest, fragments rounded to nearest, the
/// paper's 3 x 10-bit tail ([`PaperTail`]). Bit-identical to the kernel before the
/// unbiased arithmetic existed.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct Paper;

/// The default arithmetic: dithered products and fragment quantization (unbiased on
/// average, no transmittance stall) and a tail that does not saturate on dense content
/// ([`Tail`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct Unbiased;

impl Arithmetic for Paper {
    #[allow(private_interfaces)]
    const KIND: Kind = Kind::Paper;
    type Tail = PaperTail;

    /// `A = A_front + round(A_back * T_front / 255)` (saturating), `T = round(T_front * T_back / 255)`.
    #[inline(always)]
    fn merge(front: Row, back: Row) -> Row {
        let [ar, ag, ab, at] = front.rgbt();
        let [br, bg, bb, bt] = back.rgbt();
        // `min` rather than `u8::saturating_add`: the same value, without a branch.
        let add = |a: u8, b: u8| (a as u32 + mul(b, at) as u32).min(255) as u8;
        Row::new([add(ar, br), add(ag, bg), add(ab, bb)], mul(at, bt), front.depth())
    }

    #[inline(always)]
    fn quantize(fragment: &Fragment) -> Row {
        fragment.row_nearest()
    }
}

impl Arithmetic for Unbiased {
    #[allow(private_interfaces)]
    const KIND: Kind = Kind::Unbiased;
    type Tail = Tail;

    /// With `d = merge_dither(front, back)`:
    /// `T = floor((T_front * T_back + d) / 255)`,
    /// `A = A_front + floor((A_back * T_front + 254 - d) / 255)` per channel, saturating at 255.
    #[inline(always)]
    fn merge(front: Row, back: Row) -> Row {
        unbiased_merge(front, back, merge_dither(front, back))
    }

    #[inline(always)]
    fn merge_pair(a_first: bool, a: Row, b: Row) -> Row {
        let d = merge_dither(a, b); // = merge_dither(b, a): the hash is symmetric
        // Branchless, as Listing 1's swaps: the depth order of an unsorted stream is random.
        let (front, back) = (select_unpredictable(a_first, a, b), select_unpredictable(a_first, b, a));
        unbiased_merge(front, back, d)
    }

    /// To nearest, as the paper's ([`Paper::quantize`](Arithmetic::quantize)), except for faint fragments
    /// (`alpha * 255 < 16`, where half a unit of rounding is more than 3 % of the value),
    /// which are quantized with the fragment dither (`docs/layout.md`).
    ///
    /// Why only those (measured with `oit-lab faint`, 3 seeds, `docs/quality.md`): dithering
    /// every fragment doubles the quantization noise, which cost up to 1.1 dB on scenes that
    /// are already within an 8-bit step of the exact image; rounding every fragment to
    /// nearest left FOG's background visibility biased by +0.0073 on average (its faint alphas
    /// round down more often than up). Dithering the faint ones removes that bias and keeps the
    /// other scenes within 0.4 dB of the paper's rounding.
    #[inline(always)]
    fn quantize(fragment: &Fragment) -> Row {
        if fragment.alpha() * 255.0 < FAINT_BYTES {
            let c = fragment.color();
            quantize_dithered([c.x, c.y, c.z], fragment.alpha(), fragment.depth())
        } else {
            fragment.row_nearest()
        }
    }
}

/// The four bytes `[R, G, B, T]` of a row's first word, one per 16-bit slot of a `u64`.
#[inline(always)]
const fn slots16(word0: u32) -> u64 {
    let w = word0 as u64;
    (w & 0xff) | ((w & 0xff00) << 8) | ((w & 0xff_0000) << 16) | ((w & 0xff00_0000) << 24)
}

/// [`Unbiased::merge`] with its dither `d` (`0..=254`), on one pixel, SWAR: the four
/// products `A_back * T_front` (three colors) and `T_back * T_front` share the factor
/// `T_front`, so they are one 64-bit multiply of the back row's bytes in 16-bit slots
/// (each product <= 65025). Each slot then gets its dither (`254 - d` for the colors, `d` for
/// `T`) and `floor(y / 255)` as `(z + (z >> 8)) >> 8` with `z = y + 1` (exact for
/// `y <= 65279`, and `z + (z >> 8) <= 65535` stays in its slot), the front colors are added
/// (at most 510: bit 8 flags the saturation to 255) and the slots are packed back to bytes.
/// The same bytes as the per-channel formula (tested exhaustively over the products and
/// dithers, and against the reference merge).
#[inline(always)]
#[expect(clippy::cast_possible_truncation, reason = "the packed bytes are the low 32 bits")]
fn unbiased_merge(front: Row, back: Row, d: u32) -> Row {
    const ONES: u64 = 0x0001_0001_0001_0001;
    const BYTES: u64 = 0x00ff_00ff_00ff_00ff;
    let [f0, f1] = front.words();
    let [b0, _] = back.words();
    let products = slots16(b0) * (f0 >> 24) as u64;
    // Dither (and the `+ 1` of `z`): `254 - d` in the color slots, `d` in the T slot.
    let dither = ((254 - d) as u64 * (ONES >> 16)) | ((d as u64) << 48);
    let z = products + dither + ONES;
    let q = ((z + ((z >> 8) & BYTES)) >> 8) & BYTES;
    let sum = q + slots16(f0 & 0x00ff_ffff);
    let saturated = (sum | (((sum >> 8) & ONES) * 0xff)) & BYTES;
    let packed = saturated | (saturated >> 8);
    let word0 = (packed & 0xffff) | ((packed >> 16) & 0xffff_0000);
    Row::from_words([word0 as u32, f1])
}

/// The multiplier of the 16-bit mix (odd, so the mix is a bijection of the folded bits).
pub(crate) const MIX_K: u32 = 0x6a09;

/// The 16-bit mix shared by both dithers: `x` folded to 16 bits and multiplied modulo 2^16
/// (a multiplicative hash, whose high bits depend on every folded bit). A shader or a SIMD
/// unit with 16-bit lanes gets the same bits; the dithers use only the high bits.
#[inline(always)]
pub(crate) const fn mix16(x: u32) -> u32 {
    (((x ^ (x >> 16)) & 0xffff) * MIX_K) & 0xffff
}

/// The dither of a merge, in `0..=254`: a hash of all 16 bytes of the two rows.
///
/// ```text
/// x = front.word0 ^ front.word1 ^ back.word0 ^ back.word1        (Row::words)
/// s = mix16(x)                                                   (see mix16)
/// d = (s * 255) >> 16
/// ```
///
/// Over uniformly distributed `s`, each `d` in `0..=254` has probability 257/65536 or
/// 258/65536 (one value), so `E[floor((p + d) / 255)]` is within `1/65536` of `p / 255`.
#[inline(always)]
pub(crate) const fn merge_dither(front: Row, back: Row) -> u32 {
    let [f0, f1] = front.words();
    let [b0, b1] = back.words();
    (mix16(f0 ^ f1 ^ b0 ^ b1) * 255) >> 16
}

/// The dither of fragment quantization: `u = (h + 0.5) / 256` with `h` in `0..=255`, a
/// hash of the fragment's f32 bits (`h = mix16(bits(R) ^ bits(G) ^ bits(B) ^ bits(alpha)
/// ^ bits(depth)) >> 8`). `u` lies in `[1/512, 511/512]`, so a value that is exactly a byte
/// (`k / 255`, up to the f32 error of `v * 255`) quantizes to that byte, and
/// `E[floor(v * 255 + u)]` is within `1/512` of `v * 255`.
#[inline(always)]
pub(crate) fn fragment_dither(color: [f32; 3], alpha: f32, depth: f32) -> f32 {
    let x = color[0].to_bits() ^ color[1].to_bits() ^ color[2].to_bits() ^ alpha.to_bits() ^ depth.to_bits();
    ((mix16(x) >> 8) as f32 + 0.5) * (1.0 / 256.0)
}

/// A byte from a value in `[0, 1]` and a dither `u` in `(0, 1)`: `floor(v * 255 + u)` in f32
/// (multiply, then add, each rounded; truncation).
#[inline(always)]
#[expect(
    clippy::cast_possible_truncation,
    clippy::cast_sign_loss,
    reason = "v in [0, 1], u in (0, 1): v * 255 + u in [0, 256), truncated to a byte as specified"
)]
pub(crate) fn quantize_with_dither(v: f32, u: f32) -> u8 {
    (v * 255.0 + u) as u8
}

/// Alpha below which [`Unbiased`] quantizes a fragment with a dither, in bytes
/// (`alpha * 255 < 16.0`, computed in f32).
pub(crate) const FAINT_BYTES: f32 = 16.0;

/// A dithered quantization of a validated fragment (premultiplied color, alpha, depth):
/// every channel and alpha with the same dither ([`fragment_dither`]), so that a color that
/// does not exceed alpha still gives `color byte <= 255 - T byte`. Unbiased on average over
/// the dither, at twice the noise of rounding to nearest; [`Unbiased`] uses it for faint
/// fragments only. For many identical faint fragments, rounding to nearest is off in the
/// same direction every time (`tests/unbiased.rs`).
#[inline(always)]
pub(crate) fn quantize_dithered(color: [f32; 3], alpha: f32, depth: f32) -> Row {
    let u = fragment_dither(color, alpha, depth);
    Row::new(
        color.map(|c| quantize_with_dither(c, u)),
        255 - quantize_with_dither(alpha, u),
        depth,
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::unorm::div255_floor;

    /// The reference formula of the unbiased merge, for one pair of bytes and a dither.
    fn reference(a: u32, b: u32, d: u32) -> u32 {
        (a * b + d) / 255
    }

    #[test]
    fn dithered_products_are_exact_floor_for_every_pair_and_dither() {
        for a in 0..=255u32 {
            for b in 0..=255u32 {
                for d in [0, 1, 127, 253, 254] {
                    assert_eq!(div255_floor(a * b + d), reference(a, b, d), "{a} {b} {d}");
                }
            }
        }
    }

    #[test]
    fn slot_division_is_exact_floor() {
        for y in 0..=255u32 * 255 + 254 {
            let z = y + 1;
            assert!(z + (z >> 8) <= 0xffff, "{y}: the slot overflows");
            assert_eq!((z + (z >> 8)) >> 8, div255_floor(y), "{y}");
        }
    }

    /// The SWAR merge against the per-channel formula of `Unbiased::merge`'s docs, for every
    /// `T_front`, every back byte and every dither (front colors chosen to reach the
    /// saturation and stay below it).
    #[test]
    #[expect(clippy::cast_possible_truncation, reason = "bytes by construction")]
    fn swar_merge_is_the_per_channel_formula() {
        for at in 0..=255u32 {
            for b in 0..=255u32 {
                let front_c = [(b + at) & 0xff, 255 - ((b + at) & 0xff), at];
                let back_c = [b, 255 - b, b ^ 0x5a];
                let front = Row::new(front_c.map(|v| v as u8), at as u8, 1.5);
                let back = Row::new(back_c.map(|v| v as u8), b as u8, 2.5);
                for d in 0..=254u32 {
                    let c = |i: usize| (front_c[i] + (back_c[i] * at + 254 - d) / 255).min(255) as u8;
                    let expected = Row::new([c(0), c(1), c(2)], ((at * b + d) / 255) as u8, 1.5);
                    assert_eq!(unbiased_merge(front, back, d), expected, "T {at}, back {b}, d {d}");
                }
            }
        }
    }

    #[test]
    fn dither_is_in_range_and_nearly_uniform() {
        let mut hist = [0u32; 255];
        for s in 0..=0xffffu32 {
            let d = (s * 255) >> 16;
            hist[d as usize] += 1;
        }
        assert!(hist.iter().all(|&n| n == 257 || n == 258), "{hist:?}");
        assert_eq!(hist.iter().filter(|&&n| n == 258).count(), 1);
    }

    #[test]
    fn unbiased_merge_is_exact_where_the_paper_is() {
        let mut x = 0x1234_5678u32;
        for _ in 0..20_000 {
            x = x.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            let b = x.to_le_bytes();
            let front = Row::new([b[0], b[1], b[2]], b[3], (x >> 7) as f32);
            let back = Row::new([b[1], b[3], b[0]], b[2], (x >> 5) as f32 + 1.0);
            // Empty row behind: identity.
            assert_eq!(Unbiased::merge(front, Row::EMPTY), front);
            // Opaque front: nothing behind shows.
            let opaque = Row::new(front.color(), 0, front.depth());
            assert_eq!(Unbiased::merge(opaque, back), opaque);
            // Opaque back: opaque result.
            assert_eq!(
                Unbiased::merge(front, Row::new(back.color(), 0, 2.0)).transmittance(),
                0
            );
        }
    }
}
