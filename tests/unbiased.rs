//! The unbiased arithmetic (issue 9): the dithered merge against its reference formula
//! (`mlab-reference`) for every pair of bytes, scalar and lanes; the exactness the paper has; and the statistical
//! property that motivated it (no transmittance stall on faint layers).

use mlab::lanes::{self, LANES};
use mlab::{Arithmetic, Paper, Row, Unbiased, mlab as listing1};
// The documented dither and unbiased merge (`docs/layout.md`, `mlab::Unbiased::merge`),
// written again from their definitions, with plain integer division.
use mlab_reference::model::{ref_merge_dither as reference_dither, ref_merge_unbiased as reference_merge};

/// Every pair of bytes in every position of the products (front T x back byte), with
/// depths and the other bytes varying so that the dither takes many values: scalar and
/// 8-wide lanes against the reference formula.
#[test]
fn merge_matches_reference_for_every_pair_of_bytes() {
    let mut dithers = [false; 255];
    let mut lane_front = [Row::EMPTY; LANES];
    let mut lane_back = [Row::EMPTY; LANES];
    let mut lane_hash = [0u32; LANES];
    let mut n = 0;
    for a in 0..=255u32 {
        for b in 0..=255u32 {
            let k = a * 256 + b;
            let front = Row::new(
                [(k * 7) as u8, (k * 13) as u8, b as u8],
                a as u8,
                1.0 + k as f32 / 65536.0,
            );
            let back = Row::new([b as u8, (b ^ 0x5a) as u8, (255 - b) as u8], b as u8, 2.0 + k as f32);
            let h = k.wrapping_mul(0x9e37_79b9) ^ (k << 7);
            let want = reference_merge(front, back, h);
            assert_eq!(Unbiased::merge(front, back, h), want, "a = {a}, b = {b}");
            dithers[reference_dither(h) as usize] = true;
            // Lanes: a one-row array holding `front`; inserting `back` (deeper) merges.
            lane_front[n] = front;
            lane_back[n] = back;
            lane_hash[n] = h;
            n += 1;
            if n == LANES {
                let mut span = [lane_front];
                lanes::mlab_insert_hashed::<Unbiased, 1>(&mut span, &lane_back, &lane_hash, 0xff);
                for l in 0..LANES {
                    let want = reference_merge(lane_front[l], lane_back[l], lane_hash[l]);
                    assert_eq!(span[0][l], want, "lane {l}");
                }
                n = 0;
            }
        }
    }
    assert!(dithers.iter().all(|&seen| seen), "every dither value was exercised");
}

/// Exact where the paper is exact: the empty row is the identity, opaque stays opaque, the
/// invariant `color <= 255 - T` survives every merge (complementary dithers), for every
/// pair of transmittance bytes and a spread of colors; the merged depth lies between the
/// two rows' and is the front's where the back adds no opacity or the front is below the
/// centroid threshold (T 160).
#[test]
fn merge_is_exact_where_the_paper_is() {
    for tf in 0..=255u8 {
        for tb in 0..=255u8 {
            let z = tf as f32 * 0.25 + tb as f32 * 1e-3;
            for c in [0u8, 1, 127, 254, 255] {
                // Colors within coverage: color <= 255 - T.
                let cf = c.min(255 - tf);
                let cb = c.min(255 - tb);
                let front = Row::new([cf, cf / 2, 0], tf, z);
                let back = Row::new([cb, 0, cb / 3], tb, z + 1.0);
                let h = u32::from(tf) << 8 | u32::from(tb) | u32::from(c) << 16;
                let h = mlab::lowbias32(h);
                let m = Unbiased::merge(front, back, h);
                assert_eq!(Unbiased::merge(front, Row::EMPTY, h), front);
                if tf == 0 {
                    assert_eq!(m, front, "opaque front");
                }
                if tb == 0 {
                    assert_eq!(m.transmittance(), 0, "opaque back");
                }
                for ch in m.color() {
                    assert!(
                        ch as u32 <= 255 - m.transmittance() as u32,
                        "{front:?} + {back:?} = {m:?}"
                    );
                }
                assert!(
                    front.depth() <= m.depth() && m.depth() <= back.depth(),
                    "{front:?} + {back:?} = {m:?}"
                );
                if tf < 160 || tb == 255 {
                    assert_eq!(m.depth(), front.depth());
                }
            }
        }
    }
}

/// Opaque fragments converge to a z-buffer in the unbiased arithmetic, whatever the order:
/// the nearest fragment's quantized color, exactly, for M = 1, 2, 4.
#[test]
fn opaque_fragments_converge_to_a_z_buffer() {
    let mut rng = 0x2545_f491_4f6c_dd1du64;
    let mut next = || {
        rng ^= rng << 13;
        rng ^= rng >> 7;
        rng ^= rng << 17;
        rng
    };
    for _ in 0..500 {
        let n = 1 + (next() % 30) as usize;
        let rows: Vec<Row> = (0..n)
            .map(|_| {
                let b = next().to_le_bytes();
                Row::new([b[0], b[1], b[2]], 0, (next() % 1000) as f32 * 0.5)
            })
            .collect();
        // The nearest, later submission first on ties (Listing 1 puts equal depths in front).
        let nearest = rows
            .iter()
            .enumerate()
            .min_by(|(i, a), (j, b)| a.depth().total_cmp(&b.depth()).then(j.cmp(i)))
            .map(|(_, r)| *r)
            .expect("n >= 1");
        let mut a1 = [Row::EMPTY; 1];
        let mut a2 = [Row::EMPTY; 2];
        let mut a4 = [Row::EMPTY; 4];
        for &r in &rows {
            listing1::insert_with::<mlab::Unbiased, _>(&mut a1, r);
            listing1::insert_with::<mlab::Unbiased, _>(&mut a2, r);
            listing1::insert_with::<mlab::Unbiased, _>(&mut a4, r);
        }
        for front in [a1[0], a2[0], a4[0]] {
            assert_eq!(front, nearest);
        }
    }
}

/// A small generator for the statistical test (xorshift64*).
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_f491_4f6c_dd1d)
    }
}

/// Mean stored visibility (in T bytes) of `pixels` one-row arrays after `n` fragments of
/// transmittance byte `t` at random depths, and the exact expected value `255 (t/255)^n`.
fn faint_stream_mean<A: Arithmetic>(pixels: usize, n: usize, t: u8, seed: u64) -> (f64, f64) {
    let mut rng = Rng(seed);
    let mut sum = 0.0;
    for _ in 0..pixels {
        let mut rows = [Row::EMPTY; 1];
        for _ in 0..n {
            let z = (rng.next() >> 40) as f32 / 16_777_216.0 * 100.0;
            let c = (rng.next() % (255 - t as u64 + 1)) as u8;
            listing1::insert_with::<A, 1>(&mut rows, Row::new([c, c / 2, 0], t, z));
        }
        sum += rows[0].transmittance() as f64;
    }
    (sum / pixels as f64, 255.0 * (t as f64 / 255.0).powi(n as i32))
}

/// The statistical property of issue 9. Over `S` independent pixels, each crossed by `n`
/// faint fragments, the mean stored transmittance of the unbiased arithmetic equals the
/// exact product of the fragments' transmittances within
///
/// `bound = n * 2/65536 + 4 * sqrt(n / (4 S))` (in T bytes).
///
/// Derivation. One merge stores `floor((T t + d) / 255)`; for `d` uniform on the 16-bit
/// hash values mapped by `(s * 255) >> 16`, each `d` in `0..=254` has probability 257/65536
/// (one value 258/65536), so `E[stored] - T t / 255` lies within `2/65536` (bias); the
/// expectation of a product of independent unbiased steps is the product of expectations,
/// so the bias of the mean after `n` merges is at most `n * 2/65536`. Each merge adds a
/// rounding noise of variance `f (1 - f) <= 1/4` (f the fraction), which later factors
/// `t/255 <= 1` only shrink: the variance of one pixel's result is at most `n / 4`, and the
/// standard error of the mean of `S` pixels at most `sqrt(n / (4 S))`; four standard
/// errors bound the noise. The paper's round-to-nearest fails the same bound by two orders
/// of magnitude (it stalls), which the test checks too, so that the test can fail.
#[test]
fn faint_streams_do_not_stall_and_are_unbiased() {
    const S: usize = 4096;
    for (t, n, seed) in [(254u8, 1000usize, 1u64), (252, 400, 2), (250, 300, 3), (245, 200, 4)] {
        let bound = n as f64 * 2.0 / 65536.0 + 4.0 * (n as f64 / (4.0 * S as f64)).sqrt();
        let (mean, exact) = faint_stream_mean::<Unbiased>(S, n, t, seed);
        assert!(
            (mean - exact).abs() <= bound,
            "unbiased, t = {t}, n = {n}: mean {mean:.3} vs exact {exact:.3} (bound {bound:.3})"
        );
        let (paper, _) = faint_stream_mean::<Paper>(S / 16, n, t, seed);
        println!("t = {t}, n = {n}: exact {exact:.3}, unbiased {mean:.3} (bound {bound:.3}), paper {paper:.3}");
        assert!(
            (paper - exact).abs() > 10.0 * bound,
            "the paper's rounding should stall here: t = {t}, mean {paper:.3} vs exact {exact:.3}"
        );
    }
}
