//! The two arithmetics of the kernel: the paper's round-to-nearest ([`Paper`]) and the
//! default, unbiased one ([`Unbiased`]), and the fragment hash that seeds its dithers.
//!
//! Every kernel type takes the arithmetic as a type parameter that defaults to
//! [`Unbiased`]: `BlendingArray<4>` is `BlendingArray<4, Unbiased>`, and
//! `BlendingArray<4, Paper>` is the paper's arithmetic bit for bit. The arithmetic decides
//! four things, nothing else (the row layout, Listing 1's sort, Listing 2's head and the
//! resolve are the same):
//!
//! | | [`Paper`] | [`Unbiased`] (default) |
//! |---|---|---|
//! | merge products (Eq. 7-8) | `round(a * b / 255)` | `floor((a * b + d) / 255)`, `d = ((h & 0xffff) * 255) >> 16` in `0..=254` |
//! | merged depth | `z_front` | the opacity-weighted depth of the two rows when `T_front >= 160` (`docs/layout.md`), else `z_front` |
//! | fragment quantization | `floor(v * 255 + 0.5)` | the same, except faint fragments (`alpha * 255 < 16`): `floor(v * 255 + u)`, `u = ((h >> 24) + 0.5) / 256` |
//! | HT tail | [`PaperTail`]: colors 3 x 10 bit, alpha 16, count 16 | [`Tail`]: colors 3 x 13 bit, alpha 14, count 11 |
//!
//! `h` is the inserted fragment's hash in its pixel, [`fragment_hash`]`(key, pixel)`: with a
//! stable key ([`Fragment::with_key`], the primitive's id) a fragment is rounded the same way
//! in every frame, so its rounding does not re-roll while the camera moves (it reduces the
//! flicker, it does not remove it: `docs/quality.md`); without one the key is the
//! fragment's content, which changes with its depth (`docs/layout.md`, `docs/quality.md`).
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
//! estimate of the exact product and does not stall. The dither is a hash (no state, no
//! randomness source): the same fragments give the same bytes on every machine, every SIMD
//! backend and in a shader with 32-bit integers.
//!
//! Exactness is kept where the paper is exact (tested): merging with the empty row is the
//! identity (`floor((255 * t + d) / 255) = t` for `d <= 254`), an opaque row stays opaque,
//! opaque fragments converge to a z-buffer, an array with `M >= n` rows holds every fragment
//! exactly as quantized. The colors use the complementary dither `254 - d`, which keeps
//! `color <= 255 - T` an invariant of the merge, as it is for the paper's rounding.
//!
//! What the dither cannot do: when the same fragment (same key, same pixel) is submitted
//! many times into a pixel whose last row does not change, the hash is the same each time
//! and the merge is a fixed point, as with the paper's rounding. Fragments with distinct keys
//! move it.
//!
//! [`PaperTail`]: crate::hybrid::PaperTail
//! [`Tail`]: crate::hybrid::Tail

use crate::fragment::Fragment;
/// The fragment hash (`src/hash.rs`), also at the crate root.
pub use crate::hash::{fragment_hash, lowbias32};
use crate::row::Row;
use crate::tail::{PaperTail, Tail, TailFormat};
use crate::unorm::mul;

/// Which arithmetic, as a value: [`Arithmetic::KIND`] of [`Paper`] and [`Unbiased`], for code
/// that chooses the arithmetic at run time (a settings menu, a command line) or that is written
/// once for both (the kernel's lane code, a port).
///
/// The contract a port relies on: the two arithmetics are exactly these two, and a port that
/// writes the kernel's bytes (such as `mlab-gpu`'s WGSL twin) reproduces the one named here
/// (the [module docs](self) list what each decides).
///
/// ```
/// use mlab::{ArithKind, Arithmetic, Paper, Unbiased};
/// assert_eq!(Paper::KIND, ArithKind::Paper);
/// assert_eq!(Unbiased::KIND.name(), Unbiased::NAME);
/// assert_eq!(ArithKind::default(), ArithKind::Unbiased); // the kernel's default
/// ```
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum ArithKind {
    /// [`Paper`]: round to nearest, the paper's tail ([`PaperTail`]).
    Paper,
    /// [`Unbiased`] (the kernel's default): dithered merges and faint fragments (seeded by each
    /// fragment's hash in its pixel, [`fragment_hash`]), merged rows at their opacity-weighted
    /// depth, the 64-bit [`Tail`].
    #[default]
    Unbiased,
}

impl ArithKind {
    /// Both, paper first, for loops.
    pub const ALL: [ArithKind; 2] = [ArithKind::Paper, ArithKind::Unbiased];

    /// `"paper"` or `"unbiased"` ([`Arithmetic::NAME`] of the type).
    pub const fn name(self) -> &'static str {
        match self {
            ArithKind::Paper => "paper",
            ArithKind::Unbiased => "unbiased",
        }
    }
}

/// The crate's short name for [`ArithKind`] (the lane code matches on `A::KIND`).
pub(crate) use ArithKind as Kind;

impl crate::sealed::Sealed for Paper {}
impl crate::sealed::Sealed for Unbiased {}

/// The arithmetic of the merge, of fragment quantization and of the HT tail: [`Paper`] or
/// [`Unbiased`] (see the [module docs](self)). Sealed: the kernel's lane code implements
/// exactly these two.
pub trait Arithmetic:
    crate::sealed::Sealed + Copy + Default + PartialEq + Eq + core::hash::Hash + core::fmt::Debug + Send + Sync + 'static
{
    /// Which one, as a value (the lane code picks its instructions by it; a port or a
    /// run-time choice maps it to and from the type).
    const KIND: ArithKind;
    /// `"paper"` or `"unbiased"` ([`ArithKind::name`]).
    const NAME: &'static str = Self::KIND.name();
    /// The HT tail of this arithmetic.
    type Tail: TailFormat;

    /// Merge two neighbouring rows (Eq. 7-8), `front` nearer, during the insert of a
    /// fragment whose hash is `h` ([`fragment_hash`]; [`Paper`] ignores it): see
    /// [`crate::mlab::insert_hashed`] and the [module docs](self).
    fn merge(front: Row, back: Row, h: u32) -> Row;

    /// Quantize a validated fragment of hash `h` ([`Fragment::hash`]; [`Paper`] ignores it)
    /// into a row.
    fn quantize(fragment: &Fragment, h: u32) -> Row;
}

/// The paper's arithmetic: products rounded to nearest, fragments rounded to nearest, the
/// paper's 3 x 10-bit tail ([`PaperTail`]). Bit-identical to the kernel before the
/// unbiased arithmetic existed.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct Paper;

/// The default arithmetic: dithered products and fragment quantization (unbiased on
/// average, no transmittance stall) and a tail that saturates far later than the paper's
/// ([`Tail`]; [`Grid::saturated_pixels`](crate::Grid::saturated_pixels) counts where it does).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct Unbiased;

impl Arithmetic for Paper {
    const KIND: ArithKind = ArithKind::Paper;
    type Tail = PaperTail;

    /// `A = A_front + round(A_back * T_front / 255)` (saturating), `T = round(T_front * T_back / 255)`,
    /// `z = z_front`.
    #[inline(always)]
    fn merge(front: Row, back: Row, _h: u32) -> Row {
        let [ar, ag, ab, at] = front.rgbt();
        let [br, bg, bb, bt] = back.rgbt();
        // `min` rather than `u8::saturating_add`: the same value, without a branch.
        let add = |a: u8, b: u8| (a as u32 + mul(b, at) as u32).min(255) as u8;
        Row::new([add(ar, br), add(ag, bg), add(ab, bb)], mul(at, bt), front.depth())
    }

    #[inline(always)]
    fn quantize(fragment: &Fragment, _h: u32) -> Row {
        fragment.row_nearest()
    }
}

impl Arithmetic for Unbiased {
    const KIND: ArithKind = ArithKind::Unbiased;
    type Tail = Tail;

    /// With the merge dither `d = ((h & 0xffff) * 255) >> 16`:
    /// `T = floor((T_front * T_back + d) / 255)`,
    /// `A = A_front + floor((A_back * T_front + 254 - d) / 255)` per channel, saturating at 255,
    /// and `z` the opacity-weighted depth of the two rows (the program is
    /// `docs/layout.md`'s, "merged depth").
    #[inline(always)]
    fn merge(front: Row, back: Row, h: u32) -> Row {
        let merged = unbiased_merge(front, back, merge_dither(h));
        let [word0, _] = merged.words();
        Row::from_words([word0, centroid_depth(front, back)])
    }

    /// To nearest, as the paper's ([`Paper::quantize`](Arithmetic::quantize)), except for faint fragments
    /// (`alpha * 255 < 16`, where half a unit of rounding is more than 1/32 of the value),
    /// which are quantized with the fragment dither `u = ((h >> 24) + 0.5) / 256`.
    ///
    /// Why only those (measured with `oit-lab faint`, 3 seeds, `docs/quality.md`): dithering
    /// every fragment doubles the quantization noise, which cost up to 1.1 dB on scenes that
    /// are already within an 8-bit step of the exact image; rounding every fragment to
    /// nearest left FOG's background visibility biased by +0.0073 on average (its faint alphas
    /// round down more often than up). Dithering the faint ones removes that bias and keeps the
    /// other scenes within 0.4 dB of the paper's rounding.
    #[inline(always)]
    fn quantize(fragment: &Fragment, h: u32) -> Row {
        if fragment.alpha() * 255.0 < FAINT_BYTES {
            let c = fragment.color();
            quantize_dithered([c.x, c.y, c.z], fragment.alpha(), fragment.depth(), fragment_dither(h))
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

/// The dither of a merge, in `0..=254`, from the inserted fragment's hash `h`:
/// `d = ((h & 0xffff) * 255) >> 16`.
///
/// Over uniformly distributed `h & 0xffff`, each `d` in `0..=254` has probability 257/65536
/// or 258/65536 (one value), so `E[floor((p + d) / 255)]` is within `1/65536` of `p / 255`.
#[inline(always)]
pub(crate) const fn merge_dither(h: u32) -> u32 {
    ((h & 0xffff) * 255) >> 16
}

/// The dither of fragment quantization: `u = ((h >> 24) + 0.5) / 256`, from the fragment's
/// hash `h`. `u` lies in `[1/512, 511/512]`, so a value that is exactly a byte (`k / 255`,
/// up to the f32 error of `v * 255`) quantizes to that byte, and `E[floor(v * 255 + u)]` is
/// within `1/512` of `v * 255`.
#[inline(always)]
pub(crate) fn fragment_dither(h: u32) -> f32 {
    ((h >> 24) as f32 + 0.5) * (1.0 / 256.0)
}

/// Transmittance byte of the front row from which [`Unbiased`]'s merge moves the depth
/// toward the back row's ([`centroid_depth`]): a front row at least this transparent.
pub(crate) const CENTROID_MIN_T: u32 = 160;

/// The weight of the back row in the depth of a merge, in 1/65536ths (`0..=65280`): `w` of
/// the merged depth's program in `docs/layout.md` (its one description): the back row's share
/// of the merged opacity in 1/256ths, rounded down and capped. Why 1/256ths: the lanes
/// compute `floor(256 * cb / den)` as `trunc(256 * (f32(cb) / f32(den)))`, exact with no
/// correction step: the f32 quotient is within `2^-25` (relative) of `cb / den <= 1`, so
/// `256 *` it is within `2^-17` of `256 * cb / den`, whose distance to the next integer
/// below or above is 0 or at least `1 / den >= 1 / 65025 > 2^-16`.
#[inline(always)]
pub(crate) const fn centroid_weight(t_front: u32, t_back: u32) -> u32 {
    let p = t_front * t_back;
    let cb = 255 * t_front - p;
    let q = (256 * cb) / if p == 65025 { 1 } else { 65025 - p };
    let w = if q > 255 { 255 } else { q };
    if t_front >= CENTROID_MIN_T { w << 8 } else { 0 }
}

/// The order-preserving key of an f32's bits, as a signed integer: `bits` for a positive
/// sign, the low 31 bits flipped for a negative one. `a <= b` in IEEE order (not NaN) iff
/// `key(a) <= key(b)` (`-0.0` just below `+0.0`). Its own inverse.
#[inline(always)]
#[expect(clippy::cast_possible_wrap, clippy::cast_sign_loss, reason = "bit reinterpretation")]
pub(crate) const fn depth_key(bits: u32) -> i32 {
    (bits ^ (((bits as i32) >> 31) as u32 & 0x7fff_ffff)) as i32
}

/// The depth of [`Unbiased`]'s merge: the opacity-weighted depth of the two rows, moved from
/// `z_front` toward `z_back` by the back row's weight ([`centroid_weight`]), in integers on
/// the order-preserving keys of the depths ([`depth_key`]):
///
/// ```text
/// kf = key(z_front), kb = key(z_back)                 // signed
/// z  = kb > kf ? key^-1(kf + floor((kb - kf) * w / 65536)) : z_front
/// ```
///
/// (`kb - kf` as an unsigned 32-bit difference; `w` in 1/65536ths; `floor(diff * w / 65536)` is
/// `(diff >> 16) * w + (((diff & 0xffff) * w) >> 16)` in 32 bits.) The depth stays in
/// `[z_front, z_back]`, so rows stay sorted; it is `z_front` bit for bit when `w = 0` (an
/// opaque front, an empty back) or when the back row is not behind.
#[inline(always)]
#[expect(clippy::cast_possible_wrap, clippy::cast_sign_loss, reason = "bit reinterpretation")]
pub(crate) const fn centroid_depth(front: Row, back: Row) -> u32 {
    let [f0, zf] = front.words();
    let [b0, zb] = back.words();
    // Below the threshold the weight is 0 and the depth is the front's: the division and
    // the order keys are skipped (the common case once a pixel's last row is dense).
    if f0 >> 24 < CENTROID_MIN_T {
        return zf;
    }
    let w = centroid_weight(f0 >> 24, b0 >> 24);
    let (kf, kb) = (depth_key(zf), depth_key(zb));
    let diff = if kb > kf { kb.wrapping_sub(kf) as u32 } else { 0 };
    let step = (diff >> 16) * w + (((diff & 0xffff) * w) >> 16);
    depth_key(kf.wrapping_add(step as i32) as u32) as u32
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
/// every channel and alpha with the same dither `u` ([`fragment_dither`]), so that a color that
/// does not exceed alpha still gives `color byte <= 255 - T byte`. Unbiased on average over
/// the dither, at twice the noise of rounding to nearest; [`Unbiased`] uses it for faint
/// fragments only. For many identical faint fragments, rounding to nearest is off in the
/// same direction every time (`tests/unbiased.rs`).
#[inline(always)]
pub(crate) fn quantize_dithered(color: [f32; 3], alpha: f32, depth: f32, u: f32) -> Row {
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
            let h = crate::hash::lowbias32(x);
            // Empty row behind: identity.
            assert_eq!(Unbiased::merge(front, Row::EMPTY, h), front);
            // Opaque front: nothing behind shows.
            let opaque = Row::new(front.color(), 0, front.depth());
            assert_eq!(Unbiased::merge(opaque, back, h), opaque);
            // Opaque back: opaque result.
            assert_eq!(
                Unbiased::merge(front, Row::new(back.color(), 0, 2.0), h).transmittance(),
                0
            );
        }
    }

    /// The centroid weight against its definition in 64-bit arithmetic, for every pair of
    /// transmittance bytes: in `0..=65280`, 0 below the threshold and where the back row
    /// adds no opacity.
    #[test]
    fn centroid_weight_is_the_floor_of_the_share_for_every_pair() {
        for tf in 0..=255u32 {
            for tb in 0..=255u32 {
                let cb = u64::from((255 - tb) * tf);
                let af = u64::from(255 * (255 - tf));
                let want = if tf < CENTROID_MIN_T || cb == 0 {
                    0
                } else {
                    (256 * cb / (af + cb)).min(255) * 256
                };
                let w = centroid_weight(tf, tb);
                assert_eq!(u64::from(w), want, "T_f {tf} T_b {tb}");
                assert!(w <= 65280);
            }
        }
    }

    /// The depth key orders f32 as IEEE `<=` does and is its own inverse.
    #[test]
    #[expect(clippy::cast_sign_loss, reason = "bit reinterpretation")]
    fn depth_key_orders_and_inverts() {
        let values = [
            f32::NEG_INFINITY,
            -3.0e38,
            -2.5,
            -1.0,
            -1.0e-40,
            -0.0,
            0.0,
            1.0e-40,
            1.0,
            1.5,
            2.5,
            3.0e38,
            f32::INFINITY,
        ];
        for a in values {
            assert_eq!(depth_key(depth_key(a.to_bits()) as u32) as u32, a.to_bits());
            for b in values {
                if a < b {
                    assert!(depth_key(a.to_bits()) < depth_key(b.to_bits()), "{a} {b}");
                }
            }
        }
    }

    /// The merged depth for every pair of transmittance bytes and depth orders: within
    /// `[z_front, z_back]` (rows stay sorted), `z_front` bit for bit for an opaque front, an
    /// empty back, a back row that is not behind, and a front below the threshold; `z_back`
    /// approached as the front turns transparent.
    #[test]
    #[expect(clippy::cast_possible_truncation, reason = "bytes by construction")]
    fn centroid_depth_stays_between_the_rows() {
        let depths = [
            (-5.0f32, -1.0f32),
            (-1.0, 2.0),
            (0.5, 0.5),
            (1.0, 1.0e-7 + 1.0),
            (1.0, 100.0),
            (-0.0, 0.0),
            (2.0, 1.0),
        ];
        for tf in 0..=255u32 {
            for tb in 0..=255u32 {
                for (zf, zb) in depths {
                    let front = Row::new([1, 2, 3], tf as u8, zf);
                    let back = Row::new([4, 5, 6], tb as u8, zb);
                    let z = f32::from_bits(centroid_depth(front, back));
                    if zb > zf {
                        assert!(zf <= z && z <= zb, "T {tf} {tb}: {zf} {zb} -> {z}");
                    }
                    if zb <= zf || tf == 0 || tb == 255 || tf < CENTROID_MIN_T {
                        assert_eq!(z.to_bits(), zf.to_bits(), "T {tf} {tb}: {zf} {zb} -> {z}");
                    }
                }
                // An empty back row (+infinity) never moves the depth.
                assert_eq!(
                    centroid_depth(Row::new([0; 3], tf as u8, 3.0), Row::EMPTY),
                    3.0f32.to_bits()
                );
            }
        }
        // The weight is the share of opacity: a front of T 255 (no opacity) gives 255/256
        // of the way to the back row (the cap), in key space: linear within a binade.
        let z = f32::from_bits(centroid_depth(Row::new([0; 3], 255, 1.0), Row::new([9; 3], 0, 1.5)));
        assert_eq!(z, 1.0 + 0.5 * 255.0 / 256.0);
        // A third of the opacity in front: two thirds of the way, in 1/256ths.
        let w = centroid_weight(170, 0); // af = 255 * 85, cb = 255 * 170: 2/3 behind
        assert_eq!(w, (256 * 2 / 3) * 256);
    }
}
