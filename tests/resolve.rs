//! The integer RGBA8 resolve (what `Framebuffer::resolve_rgba8` writes for MLAB;
//! `docs/layout.md`, "Integer resolve") against the plain reference formula of
//! `mlab-reference` (`resolve_int`, written from the docs in `u64` with plain division), byte
//! for byte, through every MLAB framebuffer (pixel-major, spans, run-time sized; whole and
//! partial spans), and against the exact composite of the rows within the derived bound.
//!
//! Sizes (debug builds, CI): every single row (each channel sees every `(color, T)` pair:
//! 65,536 rows) over five backgrounds; at M = 2 every `(T_front, C_back)` pair of each channel
//! with the front color and back transmittance drawn from a fixed hash (65,536 pixels per
//! seed, 2 seeds: the full 2^32 pairs of rows, or 2^24 per channel, would take minutes);
//! arbitrary rows at M = 1, 2, 3, 4, 8 for the bound. About 2 s in a debug build.

use mlab::TailFormat;
use mlab::glam::Vec3;
use mlab::{Background, DynFramebuffer, Framebuffer, Layers, MlabFramebuffer, Row, SpanFramebuffer};
use mlab_reference::{Rng, resolve_int};

const BACKGROUNDS: [Background; 5] = [
    Background::Transparent,
    Background::Opaque(Vec3::new(0.2, 0.5, 1.0)),
    Background::Opaque(Vec3::ZERO),
    Background::Opaque(Vec3::ONE),
    // Not a color: clamped (NaN to 0), as to_rgba8 clamps.
    Background::Opaque(Vec3::new(f32::NAN, f32::INFINITY, -1.0)),
];

/// `pixels[i]` (M rows each, row-major `w` wide) resolved by the pixel-major, the span and
/// the run-time-sized framebuffer; each output checked against the reference, and (for a
/// background in `[0, 1]`) the reference against the exact composite within the bound.
fn check<const M: usize>(pixels: &[[Row; M]], w: u32) {
    let h = (pixels.len() as u32).div_ceil(w);
    assert_eq!(pixels.len(), (w * h) as usize);
    let n = pixels.len();
    let mut pm: Vec<Row> = pixels.iter().flatten().copied().collect();
    let pm = MlabFramebuffer::<M>::new(&mut pm, w, h).expect("size");
    let mut st = vec![Row::EMPTY; SpanFramebuffer::<M>::rows_needed(w, h).expect("size")];
    let mut sp = SpanFramebuffer::<M>::new(&mut st, w, h).expect("size");
    sp.copy_from(&pm).expect("same size");
    let mut dst = vec![Row::EMPTY; Layers::Mlab(M).rows_needed(w, h).expect("size")];
    dst.copy_from_slice(sp.as_rows());
    let dy: DynFramebuffer = DynFramebuffer::new(Layers::Mlab(M), &mut dst, w, h).expect("size");
    let mut worst = 0.0f64;
    for bg in BACKGROUNDS {
        let want: Vec<[u8; 4]> = pixels.iter().map(|p| resolve_int::rgba8(p, bg)).collect();
        for (name, fb) in [("pixel-major", &pm as &dyn Rgba8), ("spans", &sp), ("dyn", &dy)] {
            let got = fb.rgba8(n, bg);
            if let Some(i) = (0..n).find(|&i| got[i] != want[i]) {
                panic!(
                    "M = {M} {name} {bg:?} pixel {i} {:?}: {:?}, reference {:?}",
                    pixels[i], got[i], want[i]
                );
            }
        }
        let in_range = match bg {
            Background::Opaque(c) => c.to_array().iter().all(|x| (0.0..=1.0).contains(x)),
            Background::Transparent => true,
        };
        if in_range {
            for (p, w) in pixels.iter().zip(&want) {
                let exact = resolve_int::exact(p, bg);
                let bound = resolve_int::bound(p, bg);
                for ch in 0..4 {
                    let err = (f64::from(w[ch]) - exact[ch]).abs();
                    assert!(
                        err <= bound[ch] + 1e-9,
                        "M = {M} {bg:?} {p:?} channel {ch}: {} vs exact {} (bound {})",
                        w[ch],
                        exact[ch],
                        bound[ch]
                    );
                    worst = worst.max(err - 0.5);
                }
            }
        }
    }
    // The bound leaves room: the largest error beyond the output's half step, for the record.
    eprintln!("M = {M}: {n} pixels, largest error beyond 1/2 step {worst:.4} byte");
}

/// A whole-frame RGBA8 resolve of any framebuffer (object-safe for the loop above).
trait Rgba8 {
    fn rgba8(&self, n: usize, bg: Background) -> Vec<[u8; 4]>;
}
impl<F: Framebuffer> Rgba8 for F {
    fn rgba8(&self, n: usize, bg: Background) -> Vec<[u8; 4]> {
        let mut out = vec![[0u8; 4]; n];
        self.resolve_rgba8(&mut out, bg).expect("size");
        // Span by span the same bytes (the last span's lanes past the edge dropped).
        let w = self.width() as usize;
        for (y, line) in out.chunks_exact(w).enumerate() {
            for (s, px) in line.chunks(8).enumerate() {
                let span = self.resolve_span_rgba8(s as u32, y as u32, bg);
                assert_eq!(px, &span[..px.len()], "span {s} of line {y}");
            }
        }
        out
    }
}

/// Every single row: each channel sees every (color, T) pair (R = c, G = 255 - c,
/// B = c ^ 0xa5), 256 x 256 pixels.
#[test]
fn every_single_row() {
    let pixels: Vec<[Row; 1]> = (0..65536u32)
        .map(|i| {
            let (c, t) = ((i & 255) as u8, (i >> 8) as u8);
            [Row::new([c, 255 - c, c ^ 0xa5], t, 1.0)]
        })
        .collect();
    check::<1>(&pixels, 256);
}

/// M = 2: every (T_front, C_back) pair of each channel, the front color and the back
/// transmittance from a fixed hash, two seeds; and every row behind an empty one.
#[test]
fn pairs_of_rows() {
    for seed in 0..2u64 {
        let mut rng = Rng(0x22 + seed);
        let pixels: Vec<[Row; 2]> = (0..65536u32)
            .map(|i| {
                let (c, t) = ((i & 255) as u8, (i >> 8) as u8);
                let x = rng.next_u64();
                let front = Row::new([x as u8, (x >> 8) as u8, (x >> 16) as u8], t, 1.0);
                let back = Row::new([c, 255 - c, c ^ 0x3c], (x >> 24) as u8, 2.0);
                [front, back]
            })
            .collect();
        check::<2>(&pixels, 256);
    }
    let behind_empty: Vec<[Row; 2]> = (0..65536u32)
        .map(|i| [Row::EMPTY, Row::new([i as u8, (i >> 8) as u8, 0], (i >> 8) as u8, 1.0)])
        .collect();
    check::<2>(&behind_empty, 256);
}

/// Arbitrary row bytes (depth bytes too: NaN depths, unsorted rows), widths that are not
/// multiples of 8 (partial last spans), M = 1, 2, 3, 4, 8.
#[test]
fn arbitrary_rows_within_the_bound() {
    fn run<const M: usize>(rng: &mut Rng, w: u32, h: u32) {
        let pixels: Vec<[Row; M]> = (0..w * h)
            .map(|_| {
                core::array::from_fn(|_| {
                    let x = rng.next_u64();
                    match x % 8 {
                        0 => Row::EMPTY,
                        1 => Row::new([x as u8, (x >> 8) as u8, (x >> 16) as u8], 0, 1.0),
                        // A fragment-like row: color at most the coverage.
                        2..=4 => {
                            let t = (x >> 24) as u8;
                            let cov = 255 - u32::from(t);
                            let c = |s: u32| ((((x >> s) & 255) as u32 * cov) / 255) as u8;
                            Row::new([c(32), c(40), c(48)], t, 1.0)
                        }
                        _ => Row::from_bytes(x.to_le_bytes()),
                    }
                })
            })
            .collect();
        check::<M>(&pixels, w);
    }
    let mut rng = Rng(2222);
    run::<1>(&mut rng, 13, 40);
    run::<2>(&mut rng, 67, 11);
    run::<3>(&mut rng, 21, 7);
    run::<4>(&mut rng, 130, 17);
    run::<8>(&mut rng, 45, 9);
}

/// HT pixels (K head rows and a tail each): the reference integer formula (equal to the
/// kernel's scalar and lane definitions, `src/lanes/resolve_int/ht.rs` tests) against the exact
/// composite within the derived bound (backgrounds in `[0, 1]`).
fn check_ht<const K: usize, A: mlab::Arithmetic>(pixels: &[([Row; K], A::Tail)], w: u32) -> f64 {
    let h = (pixels.len() as u32).div_ceil(w);
    assert_eq!(pixels.len(), (w * h) as usize);
    let n = pixels.len();
    let _ = w;
    let mut worst = 0.0f64;
    for bg in BACKGROUNDS {
        let want: Vec<[u8; 4]> = pixels.iter().map(|(hd, t)| resolve_int::ht_rgba8(hd, *t, bg)).collect();
        let in_range = match bg {
            Background::Opaque(c) => c.to_array().iter().all(|x| (0.0..=1.0).contains(x)),
            Background::Transparent => true,
        };
        if in_range {
            for ((hd, t), w) in pixels.iter().zip(&want) {
                let exact = resolve_int::ht_exact(hd, *t, bg);
                let bound = resolve_int::ht_bound(hd, *t, bg);
                for ch in 0..4 {
                    let err = (f64::from(w[ch]) - exact[ch]).abs();
                    assert!(
                        err <= bound[ch] + 1e-9,
                        "K = {K} {bg:?} {hd:?} {t:?} channel {ch}: {} vs exact {} (bound {})",
                        w[ch],
                        exact[ch],
                        bound[ch]
                    );
                    worst = worst.max(err - 0.5);
                }
            }
        }
    }
    eprintln!("HT K = {K}: {n} pixels, largest error beyond 1/2 step {worst:.4} byte");
    worst
}

/// Every tail of one fragment: each `(C, A)` byte pair (`S_c = C` in R, `255 - C` in G,
/// `C ^ 0xa5` in B, `S_a = A`, count 1) behind no head (K = 1, an empty head row), both tails;
/// and behind a half-transparent head row.
#[test]
fn ht_every_tail_of_one_fragment() {
    fn run<A: mlab::Arithmetic>(front: Row) {
        let pixels: Vec<([Row; 1], A::Tail)> = (0..65536u32)
            .map(|i| {
                let (c, a) = (i & 255, i >> 8);
                ([front], A::Tail::from_sums([c, 255 - c, c ^ 0xa5], a, 1))
            })
            .collect();
        check_ht::<1, A>(&pixels, 256);
    }
    run::<mlab::Unbiased>(Row::EMPTY);
    run::<mlab::Paper>(Row::EMPTY);
    run::<mlab::Unbiased>(Row::new([40, 90, 10], 128, 1.0));
}

/// Every count of each tail (0..=2047 for `Tail`, 0..=65535 in steps of 7 for `PaperTail`)
/// with fixed sums: small, mid and saturated alpha, colors at and above the alpha.
#[test]
fn ht_every_count_fixed_sums() {
    for &a in &[1u32, 37, 255, 700, 4000, 16383] {
        let pixels: Vec<([Row; 0], mlab::Tail)> = (0..2048u32)
            .map(|n| ([], mlab::Tail::from_sums([a.min(8191), (3 * a).min(8191), 8191], a, n)))
            .collect();
        check_ht::<0, mlab::Unbiased>(&pixels, 64);
    }
    for &a in &[1u32, 300, 2000, 65535] {
        let pixels: Vec<([Row; 0], mlab::hybrid::PaperTail)> = (0..65536u32)
            .step_by(7)
            .take(9362)
            .map(|n| ([], mlab::hybrid::PaperTail::from_sums([a.min(1023), 1023, 0], a, n)))
            .collect();
        check_ht::<0, mlab::Paper>(&pixels, 31 * 2);
    }
}

/// Random fragment-like heads and tails accumulated from fragment-like rows (K = 3, both
/// tails), and arbitrary head and tail bytes (which must resolve, equal to the reference).
#[test]
fn ht_random_and_arbitrary() {
    fn frag_row(rng: &mut Rng) -> Row {
        let x = rng.next_u64();
        let t = (x >> 24) as u8;
        let cov = 255 - u32::from(t);
        let c = |s: u32| ((((x >> s) & 255) as u32 * cov) / 255) as u8;
        Row::new([c(32), c(40), c(48)], t, 1.0)
    }
    fn run<A: mlab::Arithmetic>(rng: &mut Rng, arbitrary: bool) {
        let pixels: Vec<([Row; 3], A::Tail)> = (0..40 * 25)
            .map(|_| {
                if arbitrary {
                    let r = |rng: &mut Rng| Row::from_bytes(rng.next_u64().to_le_bytes());
                    (
                        [r(rng), r(rng), r(rng)],
                        A::Tail::from_bytes(rng.next_u64().to_le_bytes()),
                    )
                } else {
                    let head = [frag_row(rng), frag_row(rng), frag_row(rng)];
                    let mut tail = A::Tail::EMPTY;
                    for _ in 0..rng.next_u64() % 300 {
                        tail.add(frag_row(rng));
                    }
                    (head, tail)
                }
            })
            .collect();
        if arbitrary {
            // Arbitrary bytes: the formula resolves every pattern (no panic, no overflow).
            for bg in BACKGROUNDS {
                for (hd, t) in &pixels {
                    let _ = resolve_int::ht_rgba8(hd, *t, bg);
                }
            }
        } else {
            check_ht::<3, A>(&pixels, 40);
        }
    }
    let mut rng = Rng(0x22_4854);
    run::<mlab::Unbiased>(&mut rng, false);
    run::<mlab::Paper>(&mut rng, false);
    run::<mlab::Unbiased>(&mut rng, true);
    run::<mlab::Paper>(&mut rng, true);
}

/// HT's `resolve_rgba8` through both HT framebuffers (pixel-major, spans) against the
/// reference per pixel, on lines where whole spans have empty tails and others not (the line
/// loop resolves the former alone and groups the latter: two or four spans at once), at widths
/// that leave odd groups and partial spans, both tails, every background.
#[test]
fn ht_framebuffers_mixed_empty_tails() {
    fn run<A: mlab::Arithmetic>(rng: &mut Rng, w: u32, h: u32) {
        let spans_per_line = w.div_ceil(8);
        let empty: Vec<bool> = (0..spans_per_line * h)
            .map(|_| rng.next_u64().is_multiple_of(3))
            .collect();
        let pixels: Vec<([Row; 3], A::Tail)> = (0..w * h)
            .map(|i| {
                let (x, y) = (i % w, i / w);
                let mut row = || {
                    let x = rng.next_u64();
                    let t = (x >> 24) as u8;
                    let cov = 255 - u32::from(t);
                    let c = |s: u32| ((((x >> s) & 255) as u32 * cov) / 255) as u8;
                    Row::new([c(32), c(40), c(48)], t, 1.0)
                };
                let head = [row(), row(), row()];
                let mut tail = A::Tail::EMPTY;
                let n = if empty[(y * spans_per_line + x / 8) as usize] {
                    0
                } else {
                    x * 7 % 40
                };
                for _ in 0..n {
                    tail.add(row());
                }
                (head, tail)
            })
            .collect();
        let mut pm: Vec<Row> = pixels
            .iter()
            .flat_map(|(hd, t)| hd.iter().copied().chain([Row::from_bytes(t.to_bytes())]))
            .collect();
        let pm = mlab::HybridFramebuffer::<3, A>::new(&mut pm, w, h).expect("size");
        let mut st = vec![Row::EMPTY; mlab::HybridSpanFramebuffer::<3, A>::rows_needed(w, h).expect("size")];
        let mut sp = mlab::HybridSpanFramebuffer::<3, A>::new_cleared(&mut st, w, h).expect("size");
        sp.copy_from(&pm).expect("same size");
        for bg in BACKGROUNDS {
            let want: Vec<[u8; 4]> = pixels.iter().map(|(hd, t)| resolve_int::ht_rgba8(hd, *t, bg)).collect();
            let mut out = vec![[0u8; 4]; (w * h) as usize];
            pm.resolve_rgba8(&mut out, bg).expect("size");
            assert_eq!(out, want, "pixel-major, w = {w}, {bg:?}");
            sp.resolve_rgba8(&mut out, bg).expect("size");
            assert_eq!(out, want, "spans, w = {w}, {bg:?}");
        }
    }
    let mut rng = Rng(3131);
    for (w, h) in [(1, 3), (8, 2), (13, 3), (40, 4), (83, 5), (130, 3)] {
        run::<mlab::Unbiased>(&mut rng, w, h);
        run::<mlab::Paper>(&mut rng, w, h);
    }
}
