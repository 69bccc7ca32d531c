//! The SWAR arithmetic on whole rows, written once for any register width (the `swar!`
//! macro, instantiated in `w256.rs` and `w512.rs`): the merges (Eq. 7-8) and the tail adds
//! on 16-bit slots of 64-bit rows; and their exhaustive tests (every operand combination the
//! 16-bit slots can see, on the 256-bit instantiation).

/// `[v; N]` pairs: `[a, b, a, b, ...]` (the low and high half of each wider lane).
pub(super) const fn pairs<T: Copy, const N: usize>(a: T, b: T) -> [T; N] {
    let mut out = [a; N];
    let mut i = 1;
    while i < N {
        out[i] = b;
        i += 2;
    }
    out
}

/// The SWAR arithmetic on whole rows, written once for any register width: the merges
/// (Eq. 7-8) and the tail adds on the 16-bit slots of one register of 64-bit rows, and
/// their masks and constants. The calling module provides what lowers differently by width:
/// `mul257_high(y)`, `(y * 257) >> 16` in each 16-bit slot for `y <= 65280`; `lo_hi(lo, hi)`,
/// the low dword of each 64-bit lane from `lo` and the high one from `hi`; and
/// `skip_invisible(row, tail, new)`, `tail` where `row` is invisible (no color, T = 255),
/// else `new`. `swar!(u32xN, u16x2N, u8x4N, i16x2N, u64xN/2)` defines them for
/// that width in the module that calls it: 256 bits here (four rows per register), 512 bits
/// in `src/lanes/w512.rs` (eight rows). Each row's 64-bit lane is computed alone.
macro_rules! swar {
    ($u32:ident, $u16:ident, $u8:ident, $i16:ident, $u64:ident) => {
        /// Low dword of every 64-bit lane (a row's color and transmittance; a tail's color sums).
        pub(super) const LO: $u32 = $u32::new($crate::lanes::swar::pairs(!0, 0));
        /// High dword of every 64-bit lane (a row's depth; a tail's alpha sum and count).
        pub(super) const HI: $u32 = $u32::new($crate::lanes::swar::pairs(0, !0));
        pub(super) const BYTES02: $u32 = $u32::splat(0x00ff_00ff);

        /// Copy the mask in the high dword of each 64-bit lane to the whole lane.
        #[inline(always)]
        pub(super) fn widen_hi(m: $u32) -> $u32 {
            let h = m & HI;
            h | ::bytemuck::cast::<$u64, $u32>(::bytemuck::cast::<$u32, $u64>(h) >> 32)
        }

        /// `round(x / 255)` in each 16-bit slot holding `x <= 65025`: `((x + 128) * 257) >> 16`,
        /// one add and one high multiply (`pmulhuw`). Equal to [`crate::unorm::div255`] for every
        /// such `x` (`div255_slots_is_exact` checks all of them).
        #[inline(always)]
        pub(super) fn div255_slots(x: $u16) -> $u16 {
            mul257_high(x + $u16::splat(128))
        }

        /// `T_front` in both 16-bit slots of each row's low dword (the high dword is don't-care),
        /// and the back row's bytes 0 and 2 (R, B) and 1 and 3 (G, T), one per 16-bit slot.
        #[inline(always)]
        pub(super) fn merge_operands(front: $u32, back: $u32) -> ($u16, $u16, $u16) {
            let t = (front >> 24) & $u32::splat(0xff);
            let t2: $u16 = ::bytemuck::cast(t | (t << 16));
            let even: $u16 = ::bytemuck::cast(back & BYTES02);
            let odd: $u16 = ::bytemuck::cast((back >> 8) & BYTES02);
            (t2, even, odd)
        }

        /// `A_front + products` bytewise, saturating, in every dword; the front's T byte is
        /// replaced by the product's T.
        #[inline(always)]
        pub(super) fn merge_sum(front: $u32, pe: $u16, po: $u16) -> $u32 {
            let product = ::bytemuck::cast::<$u16, $u32>(pe) | (::bytemuck::cast::<$u16, $u32>(po) << 8);
            let a_front = front & $u32::splat(0x00ff_ffff);
            ::bytemuck::cast(::bytemuck::cast::<$u32, $u8>(a_front).saturating_add(::bytemuck::cast(product)))
        }

        /// The paper's merge (Eq. 7-8) of first words, dword for dword (as
        /// [`merge_words_unbiased`]): SWAR over 16-bit slots.
        #[inline(always)]
        pub(super) fn merge_words_paper(front: $u32, back: $u32) -> $u32 {
            let (t2, even, odd) = merge_operands(front, back);
            // Each product <= 255 * 255: no carry out of its slot.
            merge_sum(front, div255_slots(even * t2), div255_slots(odd * t2))
        }

        /// The paper's merge (Eq. 7-8) for the rows of one register (the depth is the front's).
        #[inline(always)]
        pub(super) fn merge4_paper(front: $u32, back: $u32) -> $u32 {
            lo_hi(merge_words_paper(front, back), front)
        }

        /// Turns `d` in both slots into `[255 - d, d + 1]` (G slot, T slot): `(d ^ 0xffff) + 256`
        /// is `255 - d` modulo 2^16.
        // The unbiased merge's constants and function are unused in `w512.rs`, whose MLAB merge
        // (tests only: MLAB runs on these 8-wide lanes) is the scalar one per lane.
        #[allow(dead_code)]
        pub(super) const ODD_XOR: $u16 = $u16::new($crate::lanes::swar::pairs(0xffff, 0));
        #[allow(dead_code)]
        pub(super) const ODD_ADD: $u16 = $u16::new($crate::lanes::swar::pairs(256, 1));

        /// The colors and transmittance of the unbiased merge ([`Unbiased`](crate::Unbiased)):
        /// each dword of `front` and `back` a row's first word (color and T; 8 rows packed in
        /// one register, or the low dwords of rows), with their dither `d` (one per dword, in
        /// both 16-bit slots): `floor((p + d') / 255)` as `((p + d' + 1) * 257) >> 16`, with
        /// `d' = d` for T and `254 - d` for the colors. Returns the merged first words, dword
        /// for dword.
        #[inline(always)]
        #[allow(dead_code)]
        pub(super) fn merge_words_unbiased(front: $u32, back: $u32, d: $u16) -> $u32 {
            let (t2, even, odd) = merge_operands(front, back);
            let inv = $u16::splat(255) - d; // (254 - d) + 1: R and B
            let odd_d = (d ^ ODD_XOR) + ODD_ADD; // G: (254 - d) + 1, T: d + 1
            // Products <= 65025, plus at most 255: no carry out of a slot.
            let pe = mul257_high(even * t2 + inv);
            let po = mul257_high(odd * t2 + odd_d);
            merge_sum(front, pe, po)
        }

        /// [`PaperTail`](crate::hybrid::PaperTail)`::add` for the tails of one register.
        #[inline(always)]
        pub(super) fn tail_add4_paper(tail: $u32, row: $u32) -> $u32 {
            let field = $u32::splat(0x3ff);
            let byte = $u32::splat(0xff);
            let max: $i16 = $i16::splat(1023);
            // Color sums: each field + its byte, capped at 1023 (values < 2^15: i16 min is exact).
            let sat = |sum: $u32| -> $u32 { ::bytemuck::cast(::bytemuck::cast::<$u32, $i16>(sum).min(max)) };
            let r = sat((tail & field) + (row & byte));
            let g = sat(((tail >> 10) & field) + ((row >> 8) & byte));
            let b = sat(((tail >> 20) & field) + ((row >> 16) & byte));
            let word0 = r | (g << 10) | (b << 20) | (tail & $u32::splat(0xc000_0000));
            // Alpha sum += 255 - T and count += 1: two saturating u16 adds in the high dword.
            let inc = ($u32::splat(255) - (row >> 24)) | $u32::splat(1 << 16);
            let inc = ::bytemuck::cast::<$u64, $u32>(::bytemuck::cast::<$u32, $u64>(inc & LO) << 32);
            let word1: $u32 =
                ::bytemuck::cast(::bytemuck::cast::<$u32, $u16>(tail).saturating_add(::bytemuck::cast(inc)));
            let new = lo_hi(word0, word1);
            // Invisible rows (no color, T = 255) are skipped.
            skip_invisible(row, tail, new)
        }

        /// Low dword masks for the fields of the wide tail.
        pub(super) const BYTE_LO: $u32 = $u32::new($crate::lanes::swar::pairs(0xff, 0));
        pub(super) const SUM_LO: $u32 = $u32::new($crate::lanes::swar::pairs(0x1fff, 0));
        pub(super) const ALPHA_LO: $u32 = $u32::new($crate::lanes::swar::pairs(0x3fff, 0));
        pub(super) const ONE_LO: $u32 = $u32::new($crate::lanes::swar::pairs(1, 0));

        /// [`Tail`](crate::Tail)`::add` for the tails of one register (each tail one `u64`:
        /// colors at bits 0, 13, 26, alpha at 39, count at 53).
        #[inline(always)]
        pub(super) fn tail_add4_wide(tail: $u32, row: $u32) -> $u32 {
            let shr = |v: $u32, n: u64| ::bytemuck::cast::<$u64, $u32>(::bytemuck::cast::<$u32, $u64>(v) >> n);
            let shl = |v: $u32, n: u64| ::bytemuck::cast::<$u64, $u32>(::bytemuck::cast::<$u32, $u64>(v) << n);
            // Sums below 2^15 in the low 16-bit slot, zero elsewhere: i16 min is exact.
            let sat = |v: $u32, max: i16| -> $u32 {
                ::bytemuck::cast(::bytemuck::cast::<$u32, $i16>(v).min($i16::splat(max)))
            };
            let r = row & BYTE_LO;
            let g = (row >> 8) & BYTE_LO;
            let b = (row >> 16) & BYTE_LO;
            let a = ((row >> 24) ^ BYTE_LO) & BYTE_LO; // 255 - T
            let sr = sat((tail & SUM_LO) + r, 8191);
            let sg = sat(((tail >> 13) & SUM_LO) + g, 8191);
            let sb = sat((shr(tail, 26) & SUM_LO) + b, 8191);
            let sa = sat((shr(tail, 39) & ALPHA_LO) + a, 16383);
            let sn = sat(shr(tail, 53) + ONE_LO, 2047);
            let new = sr | (sg << 13) | shl(sb, 26) | shl(sa, 39) | shl(sn, 53);
            // Invisible rows (no color, T = 255) are skipped.
            skip_invisible(row, tail, new)
        }
    };
}
pub(super) use swar;

#[cfg(test)]
mod tests {
    //! The lane arithmetic helpers against plain integer formulas, for every operand
    //! combination they can see (16-bit slots, the SWAR tail fields), so that a backend whose
    //! `wide` lowering differs shows up on the first run, before any randomized test.
    use super::super::w256::*;
    use crate::row::Row;
    use bytemuck::cast;
    use wide::{u16x16, u32x8};

    /// Four whole rows (or tails) as the `u64` lanes of one register.
    fn pack(v: [u64; 4]) -> u32x8 {
        cast(v)
    }

    fn unpack(x: u32x8) -> [u64; 4] {
        cast(x)
    }

    #[test]
    fn div255_slots_is_exact() {
        for x in 0..=255u32 * 255 {
            let got = div255_slots(u16x16::splat(x as u16)).to_array();
            assert!(got.iter().all(|&q| q as u32 == crate::unorm::div255(x)), "x = {x}");
        }
    }

    /// A front row with transmittance `tf` and colors that exercise the saturating add.
    fn front(tf: u32, salt: u32) -> u64 {
        let c = (tf * 37 + salt * 11) & 0xff;
        Row::new([c as u8, (c ^ 0x80) as u8, (255 - c) as u8], tf as u8, -(salt as f32)).to_le_u64()
    }

    /// The back row for byte `b`: every channel sees every byte value as `b` runs over 0..256.
    fn back(b: u32) -> u64 {
        Row::new([b as u8, (b ^ 0x5a) as u8, (b ^ 0xa5) as u8], (b ^ 0x3c) as u8, 7.5).to_le_u64()
    }

    /// The merge of `front` and `back` with products `p(a, b)` (colors) and `q(a, b)` (T).
    fn merged(front: u64, back: u64, p: impl Fn(u32, u32) -> u32, q: impl Fn(u32, u32) -> u32) -> u64 {
        let f = Row::from_le_u64(front);
        let b = Row::from_le_u64(back);
        let [fr, fg, fb, ft] = f.rgbt().map(u32::from);
        let [br, bg, bb, bt] = b.rgbt().map(u32::from);
        let add = |a: u32, x: u32| (a + p(x, ft)).min(255) as u8;
        Row::new([add(fr, br), add(fg, bg), add(fb, bb)], q(bt, ft) as u8, f.depth()).to_le_u64()
    }

    /// The paper's merge in 16-bit slots: every (T_front, back byte) pair in every channel.
    #[test]
    fn merge4_paper_is_exact_for_every_operand_pair() {
        let round = |x: u32, t: u32| (x * t + 127) / 255; // 255 is odd: never a tie
        for tf0 in (0..256).step_by(4) {
            let tfs = [tf0, tf0 + 1, tf0 + 2, tf0 + 3];
            for b in 0..256 {
                let fr = tfs.map(|t| front(t, b));
                let got = unpack(merge4_paper(pack(fr), pack([back(b); 4])));
                for i in 0..4 {
                    assert_eq!(
                        got[i],
                        merged(fr[i], back(b), round, round),
                        "T_front {}, b {b}",
                        tfs[i]
                    );
                }
            }
        }
    }

    /// The unbiased merge in 16-bit slots: every (T_front, back byte, dither) triple in every
    /// channel, `floor((x * T_front + 254 - d) / 255)` for colors, `floor((T * T_front + d) /
    /// 255)` for T.
    #[test]
    fn merge_words_unbiased_is_exact_for_every_operand_triple() {
        for tf in 0..256 {
            for d0 in (0..255).step_by(4) {
                let ds: [u32; 4] = core::array::from_fn(|i| (d0 + i as u32).min(254));
                // `d` in both 16-bit slots of each row's low dword (as `Dither8` holds it).
                let dv: u16x16 = cast(pack(ds.map(|d| (d | d << 16) as u64)));
                for b in 0..256 {
                    let fr = [front(tf, b); 4];
                    let got = unpack(lo_hi(merge_words_unbiased(pack(fr), pack([back(b); 4]), dv), pack(fr)));
                    for (i, &d) in ds.iter().enumerate() {
                        let want = merged(fr[i], back(b), |x, t| (x * t + 254 - d) / 255, |x, t| (x * t + d) / 255);
                        assert_eq!(got[i], want, "T_front {tf}, b {b}, d {d}");
                    }
                }
            }
        }
    }

    /// `min(s + x, max)`.
    fn sat(s: u64, x: u64, max: u64) -> u64 {
        (s + x).min(max)
    }

    /// A row of color bytes `c` and alpha byte `a` (T = 255 - a); invisible when all are 0.
    fn row(c: [u32; 3], a: u32) -> u64 {
        Row::new(c.map(|v| v as u8), (255 - a) as u8, 1.0).to_le_u64()
    }

    /// Four rows for byte `x`: as `x` runs over 0..256 each lane's color and alpha bytes take
    /// every value; lane 3 is the invisible row (no color, T = 255) when `x == 0`.
    fn rows4(x: u32) -> [u64; 4] {
        [
            row([x, x ^ 0x81, 255 - x], x),
            row([255 - x, x, x], 255 - x),
            row([x, 0, x], x ^ 0xf0),
            row([x; 3], x),
        ]
    }

    /// `add` on four tails and the rows of [`rows4`]`(x)` against `want(lane, [R, G, B, alpha])`
    /// for visible rows; invisible rows leave the tail unchanged.
    fn check_tail_add(add: fn(u32x8, u32x8) -> u32x8, tails: [u64; 4], x: u32, want: impl Fn(usize, [u64; 4]) -> u64) {
        let rows = rows4(x);
        let got = unpack(add(pack(tails), pack(rows)));
        for i in 0..4 {
            let r = Row::from_le_u64(rows[i]);
            let [cr, cg, cb, t] = r.rgbt().map(u64::from);
            let expected = if r.is_invisible() {
                tails[i]
            } else {
                want(i, [cr, cg, cb, 255 - t])
            };
            assert_eq!(got[i], expected, "tail {:#x}, row {:#x}", tails[i], rows[i]);
        }
    }

    /// The wide tail add: every (field value, byte) pair of every field (colors 0..8192,
    /// alpha 0..16384, count 0..2048 with a visible row), and invisible rows skipped.
    #[test]
    fn tail_add4_wide_is_exact_for_every_operand_pair() {
        let tail = |c: [u64; 3], a: u64, n: u64| c[0] | c[1] << 13 | c[2] << 26 | a << 39 | n << 53;
        for s0 in (0..16384u64).step_by(4) {
            let ss = [s0, s0 + 1, s0 + 2, s0 + 3];
            let cs = ss.map(|s| [s & 8191, (s * 3 + 1) & 8191, (s ^ 8191) & 8191]);
            let tails: [u64; 4] = core::array::from_fn(|i| tail(cs[i], ss[i], ss[i] & 2047));
            for x in 0..256u32 {
                check_tail_add(tail_add4_wide, tails, x, |i, [r, g, b, a]| {
                    let c = cs[i];
                    tail(
                        [sat(c[0], r, 8191), sat(c[1], g, 8191), sat(c[2], b, 8191)],
                        sat(ss[i], a, 16383),
                        sat(ss[i] & 2047, 1, 2047),
                    )
                });
            }
        }
    }

    /// The paper's tail add: every (color sum 0..1024, byte) pair, every (alpha sum, byte)
    /// pair for alpha sums 0..65536 and every count 0..65536, spare bits kept, invisible rows
    /// skipped.
    #[test]
    fn tail_add4_paper_is_exact_for_every_operand_pair() {
        let tail =
            |c: [u64; 3], spare: u64, a: u64, n: u64| c[0] | c[1] << 10 | c[2] << 20 | spare << 30 | a << 32 | n << 48;
        for s0 in (0..65536u64).step_by(4) {
            let ss = [s0, s0 + 1, s0 + 2, s0 + 3];
            let cs = ss.map(|s| [s & 1023, (s >> 6) & 1023, (s ^ 1023) & 1023]);
            let tails: [u64; 4] = core::array::from_fn(|i| tail(cs[i], ss[i] & 3, ss[i], 65535 - ss[i]));
            for x in 0..256u32 {
                check_tail_add(tail_add4_paper, tails, x, |i, [r, g, b, a]| {
                    let c = cs[i];
                    tail(
                        [sat(c[0], r, 1023), sat(c[1], g, 1023), sat(c[2], b, 1023)],
                        ss[i] & 3,
                        sat(ss[i], a, 65535),
                        sat(65535 - ss[i], 1, 65535),
                    )
                });
            }
        }
    }
}
