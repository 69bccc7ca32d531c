//! The integer RGBA8 resolves in lanes (`crate::resolve::int` is their definition): MLAB's
//! in 16-bit lanes, in two forms chosen by the build, and HT's (`ht.rs`).
//!
//! MLAB's form: `ssse3.rs` (a byte shuffle and `pmulhrsw` per layer) everywhere but x86
//! without SSSE3 (the x86-64 baseline, SSE2), where `wide` would emulate those lane by lane
//! (several times the cost of the resolve itself: `docs/performance.md`, resolves) and
//! `sse2.rs` has a form of its own.

/// `$e` with the const `$opaque` true and `$bg` the background's channels for an opaque
/// background, else with `$opaque` false and `$bg` zero: the background's case chosen once,
/// outside the loops of the resolve it picks.
macro_rules! by_background {
    ($background:expr, |$opaque:ident, $bg:ident| $e:expr) => {
        match $background {
            Some($bg) => {
                const $opaque: bool = true;
                $e
            }
            None => {
                const $opaque: bool = false;
                let $bg = [0; 3];
                $e
            }
        }
    };
}

pub(super) mod ht;
#[cfg(all(any(target_arch = "x86", target_arch = "x86_64"), not(target_feature = "ssse3")))]
mod sse2;
#[cfg(not(all(any(target_arch = "x86", target_arch = "x86_64"), not(target_feature = "ssse3"))))]
mod ssse3;

#[cfg(all(any(target_arch = "x86", target_arch = "x86_64"), not(target_feature = "ssse3")))]
use sse2 as int8;
#[cfg(not(all(any(target_arch = "x86", target_arch = "x86_64"), not(target_feature = "ssse3"))))]
use ssse3 as int8;

use super::{LANES, MlabSpan};
use crate::resolve::int::IntBackground;
use crate::row::Row;
use crate::tail::TailFormat;

/// 8 MLAB pixels of `M` rows as the integer resolve reads them: layer-major (a stored span,
/// `&MlabSpan<M>`) or pixel-major ([`PixelCell`]).
pub(crate) trait Cell<const M: usize> {
    /// The 8 rows of layer `j < M`.
    fn layer(&self, j: usize) -> [Row; LANES];
}

impl<const M: usize> Cell<M> for &MlabSpan<M> {
    #[inline(always)]
    fn layer(&self, j: usize) -> [Row; LANES] {
        self.get(j).copied().unwrap_or([Row::EMPTY; LANES])
    }
}

/// 8 pixels stored pixel-major (`pixels[lane][layer]`), read without a transpose.
#[derive(Clone, Copy)]
pub(crate) struct PixelCell<'a, const M: usize>(pub(crate) &'a [[Row; M]; LANES]);

impl<const M: usize> Cell<M> for PixelCell<'_, M> {
    #[inline(always)]
    fn layer(&self, j: usize) -> [Row; LANES] {
        core::array::from_fn(|p| self.0[p].get(j).copied().unwrap_or(Row::EMPTY))
    }
}

/// The integer RGBA8 resolve of 8 MLAB pixels (`docs/layout.md`, "Integer resolve"; what
/// [`Framebuffer::resolve_rgba8`](crate::Framebuffer::resolve_rgba8) writes for MLAB), in
/// 16-bit lanes: byte-identical to the scalar `resolve::int::rgba8` of each pixel.
#[inline(always)]
pub(crate) fn mlab_resolve_rgba8<const M: usize>(cell: impl Cell<M>, background: IntBackground) -> [[u8; 4]; LANES] {
    by_background!(background, |O, bg| int8::resolve::<M, O>(cell, bg))
}

/// [`mlab_resolve_rgba8`] of the whole spans of a line into `out`, the background's case
/// chosen once.
#[inline(always)]
pub(crate) fn mlab_resolve_line_rgba8<const M: usize, C: Cell<M>>(
    cells: impl Iterator<Item = C>,
    out: &mut [[[u8; 4]; LANES]],
    background: IntBackground,
) {
    let pairs = out.iter_mut().zip(cells);
    by_background!(background, |O, bg| pairs
        .for_each(|(o, c)| *o = int8::resolve::<M, O>(c, bg)))
}

/// The HT resolve of separate head layers and tails straight to RGBA8: the integer resolve
/// (`docs/layout.md`, "Integer resolve of HT"), byte-identical to the scalar
/// `resolve::int::ht_rgba8` of each pixel.
#[inline(always)]
pub(crate) fn hybrid_resolve_parts_rgba8<T: TailFormat, const K: usize>(
    head: &[[Row; LANES]; K],
    tails: &[T; LANES],
    background: IntBackground,
) -> [[u8; 4]; LANES] {
    by_background!(background, |O, bg| ht::resolve::<T, K, O>(head, tails, bg))
}

/// [`hybrid_resolve_parts_rgba8`] of a span whose tails are all empty (every bit zero): the
/// resolve of its head rows.
#[inline(always)]
pub(crate) fn hybrid_resolve_head_rgba8<const K: usize>(
    head: &[[Row; LANES]; K],
    background: IntBackground,
) -> [[u8; 4]; LANES] {
    by_background!(background, |O, bg| ht::resolve_head::<K, O>(head, bg))
}

#[cfg(test)]
#[expect(
    clippy::cast_possible_truncation,
    reason = "test bytes cut from wider integers on purpose"
)]
mod tests {
    //! The integer resolve: lanes (both arrangements) against the scalar definition, byte for
    //! byte, on every backend the unit tests run on; the exact cases of `docs/layout.md`.
    use crate::lanes::{self, LANES};
    use crate::resolve::int;
    use crate::resolve::*;
    use crate::row::Row;
    use glam::Vec3;

    /// A deterministic generator (SplitMix64).
    struct Mix(u64);
    impl Mix {
        fn next(&mut self) -> u64 {
            self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
            let mut z = self.0;
            z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
            z ^ (z >> 31)
        }
        /// Any 8 bytes, or (one time in four each) an empty, an opaque or an invisible row.
        fn row(&mut self) -> Row {
            let x = self.next();
            let r = Row::from_bytes(x.to_le_bytes());
            match x >> 62 {
                0 => Row::EMPTY,
                1 => Row::new([x as u8, (x >> 8) as u8, (x >> 16) as u8], 0, 1.0),
                _ => r,
            }
        }
    }

    const BACKGROUNDS: [Background; 5] = [
        Background::Transparent,
        Background::Opaque(Vec3::new(0.2, 0.5, 1.0)),
        Background::Opaque(Vec3::ZERO),
        Background::Opaque(Vec3::ONE),
        Background::Opaque(Vec3::new(f32::NAN, f32::INFINITY, -1.0)),
    ];

    fn check<const M: usize>(mix: &mut Mix) {
        let pixels: [[Row; M]; LANES] = core::array::from_fn(|_| core::array::from_fn(|_| mix.row()));
        let span: [[Row; LANES]; M] = core::array::from_fn(|j| core::array::from_fn(|p| pixels[p][j]));
        for bg in BACKGROUNDS {
            let want = pixels.map(|p| int::rgba8(&p, bg));
            assert_eq!(
                lanes::mlab_resolve_rgba8(&span, int::background(bg)),
                want,
                "M = {M} spans {bg:?}: {pixels:?}"
            );
            assert_eq!(
                lanes::mlab_resolve_rgba8(lanes::PixelCell(&pixels), int::background(bg)),
                want,
                "M = {M} pixel-major {bg:?}: {pixels:?}"
            );
        }
    }

    #[test]
    fn lanes_match_scalar_byte_for_byte() {
        let mut mix = Mix(22);
        for _ in 0..400 {
            check::<1>(&mut mix);
            check::<2>(&mut mix);
            check::<3>(&mut mix);
            check::<4>(&mut mix);
            check::<8>(&mut mix);
        }
        // Saturation: 300 bright additive rows (the accumulators stop at 32767).
        let bright = [[Row::new([255, 200, 1], 255, 1.0); LANES]; 300];
        let want = int::rgba8(&[Row::new([255, 200, 1], 255, 1.0); 300], Background::Transparent);
        // Each `T = 255` row lowers `v` by one unit while `v > 16384` (docs/layout.md): 300
        // of them leave alpha 2 (255 * 300 / 32767 = 2.3).
        assert_eq!(want, [255, 255, 255, 2]);
        assert_eq!(lanes::mlab_resolve_rgba8(&bright, None), [want; LANES]);
    }

    /// Every single row (each channel sees every (color, T) pair) in lanes and scalar.
    #[test]
    fn every_single_row_in_lanes() {
        for t in 0..=255u8 {
            for c0 in (0..256).step_by(LANES) {
                let rows: [Row; LANES] = core::array::from_fn(|i| {
                    let c = (c0 + i) as u8;
                    Row::new([c, 255 - c, c ^ 0xa5], t, 1.0)
                });
                for bg in BACKGROUNDS {
                    let want = rows.map(|r| int::rgba8(&[r], bg));
                    assert_eq!(lanes::mlab_resolve_rgba8(&[rows], int::background(bg)), want);
                }
            }
        }
    }

    #[test]
    fn exact_cases() {
        // An empty pixel is a byte background exactly; any number of empty rows too.
        for k in 0..=255u8 {
            let bg = Background::Opaque(Vec3::splat(k as f32 / 255.0));
            assert_eq!(int::rgba8(&[], bg), [k, k, k, 255]);
            assert_eq!(int::rgba8(&[Row::EMPTY; 8], bg), [k, k, k, 255]);
        }
        // An opaque row shows its bytes, and hides what is behind it.
        for c in 0..=255u8 {
            let front = Row::new([c, 255 - c, c / 3], 0, 1.0);
            for bg in [Background::Transparent, Background::Opaque(Vec3::ONE)] {
                let want = [c, 255 - c, c / 3, 255];
                assert_eq!(int::rgba8(&[front], bg), want);
                assert_eq!(int::rgba8(&[front, Row::new([255; 3], 0, 2.0)], bg), want);
            }
        }
        // The alpha formula rounds `255 (1 - v / 32767)` to nearest for every v.
        for v in 0..=int::VIS_ONE {
            let a = int::pixel([0; 3], v, None)[3] as f64;
            let exact = 255.0 * (1.0 - v as f64 / 32767.0);
            assert!((a - exact).abs() <= 0.5 + 1.0 / 128.0, "v = {v}: {a} vs {exact}");
        }
    }
}
