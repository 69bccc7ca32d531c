//! The lane traits ([`crate::vector`]) for eight rows in one 512-bit register: a layer of a
//! span (8 rows of 8 bytes) is one `u32x16`, each 64-bit lane one whole row. The SWAR
//! arithmetic is the one of `src/lanes/swar.rs` (`swar!`), instantiated for 512-bit types.
//!
//! The HT span inserts (Listing 2) use these lanes when the build has `avx512f` and
//! `avx512bw` (`x86-64-v4`), where `wide` keeps every type here in one `zmm` register: one
//! compare, one blend and one load or store per layer instead of two of each. Listing 1 (MLAB)
//! keeps the 8-wide lanes there: these lanes run it too (and the tests below check them),
//! but measured slower on a Zen 4, whose 512-bit operations take two passes of its 256-bit
//! units (`docs/performance.md`). Elsewhere `wide` splits the same types into 256-bit (AVX2)
//! or 128-bit (SSE2, NEON, simd128) parts or plain arrays, so that this source is tested on
//! every backend (`tests` below, against the 8-wide lanes of `w256.rs`), while the span API
//! keeps the 8-wide lanes there.
#![cfg_attr(not(all(target_feature = "avx512f", target_feature = "avx512bw")), allow(dead_code))]

use super::LANES;
use crate::arith::{Arithmetic, Kind};
use crate::row::Row;
use crate::tail::{Layout, TailFormat};
use crate::vector::{Layer8, RowLanes};
use bytemuck::cast;
use wide::{f32x16, f64x8, i16x32, u8x64, u16x32, u32x16, u64x8};

super::swar::swar!(u32x16, u16x32, u8x64, i16x32, u64x8);

/// `(lo & LO) | (hi & HI)`, as a select of dwords by a constant mask (one `vpblendmd`
/// instead of two ANDs and an OR; on other backends the same bits).
#[inline(always)]
fn lo_hi(lo: u32x16, hi: u32x16) -> u32x16 {
    cast(cast::<u32x16, f32x16>(HI).select(cast::<u32x16, f32x16>(hi), cast::<u32x16, f32x16>(lo)))
}

/// `tail` in the lanes where `row` is invisible (no color, T = 255), else `new`: one 64-bit
/// compare gives the whole-lane mask.
#[inline(always)]
fn skip_invisible(row: u32x16, tail: u32x16, new: u32x16) -> u32x16 {
    let low = cast::<u32x16, u64x8>(row) & u64x8::splat(0xffff_ffff);
    let invisible = cast::<u64x8, f64x8>(low.simd_eq(u64x8::splat(0xff00_0000)));
    cast(invisible.select(cast::<u32x16, f64x8>(tail), cast::<u32x16, f64x8>(new)))
}

/// `(y * 257) >> 16` in each 16-bit slot for `y <= 65280`, as `(y + (y >> 8)) >> 8` (`wide`
/// 1.7 has no 512-bit `pmulhuw`: its `u16x32::mul_keep_high` goes through four 128-bit
/// parts). Equal: with `y = 256 a + b` (`b < 256`), `y * 257 = 65536 a + 256 (a + b) + b`, so
/// both sides are `a + floor((a + b) / 256)` (`b / 65536` never carries `256 (a + b)` past a
/// multiple of 65536); `y + (y >> 8) <= 65535` needs `y <= 65280`. The merges' operands are
/// at most 65025 + 255 (`x8`'s exhaustive merge tests run these lanes too).
#[inline(always)]
fn mul257_high(y: u16x32) -> u16x32 {
    (y + (y >> 8)) >> 8
}

/// Eight rows (or eight tails) in one register, one whole row per 64-bit lane (`word0` in
/// the low dword, `word1` in the high dword).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Rows8 {
    v: u32x16,
}

/// Per-lane mask for [`Rows8`]: all ones or all zeros over each 64-bit lane (with AVX, only
/// the sign bit of each 64-bit lane is meaningful: see [`SIGN_SELECT`]).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Mask8 {
    v: u32x16,
}

impl core::ops::BitAnd for Mask8 {
    type Output = Mask8;
    #[inline(always)]
    fn bitand(self, rhs: Mask8) -> Mask8 {
        Mask8 { v: self.v & rhs.v }
    }
}

impl Mask8 {
    /// Every lane on.
    pub(super) const ALL: Mask8 = Mask8 { v: u32x16::MAX };

    /// From a bitmask (bit `i` = lane `i`).
    #[inline(always)]
    pub(super) fn from_bits(bits: u8) -> Mask8 {
        let v = u32x16::splat(bits as u32);
        let s = u32x16::new([1, 1, 2, 2, 4, 4, 8, 8, 16, 16, 32, 32, 64, 64, 128, 128]);
        Mask8 { v: (v & s).simd_eq(s) }
    }
}

impl Rows8 {
    #[inline(always)]
    pub(super) fn load(rows: &[Row; LANES]) -> Rows8 {
        Rows8 { v: cast(*rows) }
    }
}

impl Layer8 for Rows8 {
    #[inline(always)]
    fn from_rows(rows: [Row; LANES]) -> Rows8 {
        Rows8 { v: cast(rows) }
    }
    #[inline(always)]
    fn to_rows(self) -> [Row; LANES] {
        cast(self.v)
    }
}

/// With AVX, a select of whole rows is a blend on the sign bit of each 64-bit lane (`f64x8`:
/// `vpmovq2m` and `vblendmpd` with AVX-512, `vblendvpd` with AVX), that is the depth dword's
/// compare result: the masks need no widening. Without AVX the select is bitwise and the
/// masks are widened to whole lanes. Both give the same rows.
const SIGN_SELECT: bool = cfg!(target_feature = "avx");

impl RowLanes for Rows8 {
    type Mask = Mask8;
    type Tail<T: TailFormat> = Rows8;
    type Hash = [u32; LANES];
    #[inline(always)]
    fn depth_le(self, other: Self) -> Mask8 {
        let m = cast::<f32x16, u32x16>(cast::<u32x16, f32x16>(self.v).simd_le(cast::<u32x16, f32x16>(other.v)));
        // Only the high (depth) dword of each lane is meaningful.
        Mask8 {
            v: if SIGN_SELECT { m } else { widen_hi(m) },
        }
    }
    #[inline(always)]
    fn select(mask: Mask8, x: Self, y: Self) -> Self {
        let v = if SIGN_SELECT {
            cast(cast::<u32x16, f64x8>(mask.v).select(cast::<u32x16, f64x8>(x.v), cast::<u32x16, f64x8>(y.v)))
        } else {
            mask.v.select(x.v, y.v)
        };
        Rows8 { v }
    }
    /// MLAB runs on the 8-wide lanes of `w256.rs` (faster: `docs/performance.md`); these
    /// lanes hold only Listing 2's span inserts, which never merge. This merge, for the
    /// tests that run Listing 1 on both widths, is the paper's in SWAR and the scalar
    /// [`Unbiased`](crate::Unbiased) merge lane by lane.
    #[inline(always)]
    fn merge<A: Arithmetic>(front: Self, back: Self, h: [u32; LANES]) -> Self {
        match A::KIND {
            Kind::Paper => Rows8 {
                v: merge4_paper(front.v, back.v),
            },
            Kind::Unbiased => {
                let (f, b) = (front.to_rows(), back.to_rows());
                Rows8::from_rows(core::array::from_fn(|i| A::merge(f[i], b[i], h[i])))
            }
        }
    }
    #[inline(always)]
    fn tail_add<T: TailFormat>(tail: Rows8, row: Self) -> Rows8 {
        let v = match T::LAYOUT {
            Layout::Paper => tail_add4_paper(tail.v, row.v),
            Layout::Wide => tail_add4_wide(tail.v, row.v),
        };
        Rows8 { v }
    }
    #[inline(always)]
    fn select_tail<T: TailFormat>(mask: Mask8, x: Rows8, y: Rows8) -> Rows8 {
        Self::select(mask, x, y)
    }
}

#[cfg(test)]
mod tests {
    //! These lanes against the 8-wide lanes of `w256.rs` (which `tests/lanes.rs` checks against
    //! the scalar kernel) through Listings 1 and 2, on every backend: on x86-64-v4 the span API
    //! runs these lanes and `tests/lanes.rs` checks them against the scalar kernel directly.
    use super::super::w256;
    use super::*;
    use crate::arith::{Paper, Unbiased};
    use crate::hybrid::PaperTail;
    use crate::tail::Tail;

    /// xorshift64.
    struct Rng(u64);
    impl Rng {
        fn next(&mut self) -> u64 {
            self.0 ^= self.0 << 13;
            self.0 ^= self.0 >> 7;
            self.0 ^= self.0 << 17;
            self.0
        }
    }

    /// A row that often shares its depth with others (ties, `-0.0` and `0.0`), is invisible,
    /// has a NaN or infinite depth, or saturates its bytes; otherwise random bits.
    fn row(rng: &mut Rng) -> Row {
        let r = rng.next();
        let depths = [0.0, -0.0, 1.0, 1.5, -2.0, f32::NAN, f32::INFINITY, f32::NEG_INFINITY];
        let word0 = match r % 5 {
            0 => 0xff00_0000, // invisible
            1 => 0x00ff_ffff | ((r >> 8) as u32 & 0xff00_0000),
            _ => (r >> 32) as u32,
        };
        let word1 = match (r >> 3) % 4 {
            0 => depths[(r >> 5) as usize % depths.len()].to_bits(),
            1 => (r >> 8) as u32 & 3, // four distinct (subnormal) depths: ties
            _ => rng.next() as u32,
        };
        Row::from_words([word0, word1])
    }

    fn layer(rng: &mut Rng) -> [Row; LANES] {
        core::array::from_fn(|_| row(rng))
    }

    fn mask(rng: &mut Rng) -> u8 {
        match rng.next() % 3 {
            0 => 0xff,
            _ => rng.next() as u8,
        }
    }

    fn check_mlab<A: Arithmetic, const M: usize>(rng: &mut Rng) {
        for _ in 0..20_000 {
            let mut wide: [[Row; LANES]; M] = core::array::from_fn(|_| layer(rng));
            let mut narrow = wide;
            let rows = layer(rng);
            let m = mask(rng);
            let h: [u32; LANES] = core::array::from_fn(|_| rng.next() as u32);
            crate::mlab::insert_lanes::<A, _, _, M>(&mut wide, Rows8::load(&rows), Mask8::from_bits(m), h);
            let d = w256::Dither8::new(&h);
            crate::mlab::insert_lanes::<A, _, _, M>(
                &mut narrow,
                w256::Rows8::load(&rows),
                w256::Mask8::from_bits(m),
                d,
            );
            assert_eq!(wide, narrow, "M = {M}, mask {m:#x}, rows {rows:?}");
        }
    }

    fn check_hybrid<T: TailFormat, const K: usize>(rng: &mut Rng) {
        for _ in 0..20_000 {
            let mut head: [[Row; LANES]; K] = core::array::from_fn(|_| layer(rng));
            let mut tails: [T; LANES] = core::array::from_fn(|_| {
                let bits = match rng.next() % 4 {
                    0 => 0,
                    1 => !0 >> (rng.next() % 64),
                    _ => rng.next(),
                };
                cast(bits)
            });
            let (mut head8, mut tails8) = (head, tails);
            let rows = layer(rng);
            let m = mask(rng);
            crate::hybrid::insert_lanes::<_, _, _, T, K>(
                &mut head,
                &mut tails,
                Rows8::load(&rows),
                Mask8::from_bits(m),
            );
            crate::hybrid::insert_lanes::<_, _, _, T, K>(
                &mut head8,
                &mut tails8,
                w256::Rows8::load(&rows),
                w256::Mask8::from_bits(m),
            );
            assert_eq!(head, head8, "K = {K}, mask {m:#x}, rows {rows:?}");
            assert!(tails == tails8, "K = {K}, mask {m:#x}, rows {rows:?}: tails differ");
        }
    }

    /// Both inserts on 16 lanes against the 8-wide lanes (each its own stream of cases).
    #[test]
    fn inserts_match_the_8_wide_lanes() {
        macro_rules! check {
            ($rng:ident, $f:ident, $a:ty: $($n:literal)*) => { $($f::<$a, $n>($rng);)* };
        }
        let rng = &mut Rng(0x9e37_79b9_7f4a_7c15);
        check!(rng, check_mlab, Unbiased: 1 2 3 4 8);
        check!(rng, check_mlab, Paper: 1 4 5);
        let rng = &mut Rng(0x2545_f491_4f6c_dd1d);
        check!(rng, check_hybrid, Tail: 1 3 7);
        check!(rng, check_hybrid, PaperTail: 1 3);
    }

    /// [`mul257_high`] against `(y * 257) >> 16` for every `y` it is specified for.
    #[test]
    fn mul257_high_is_exact() {
        for y in 0..=65280u32 {
            let got = mul257_high(u16x32::splat(y as u16)).to_array();
            assert!(got.iter().all(|&q| q as u32 == (y * 257) >> 16), "y = {y}");
        }
    }
}
