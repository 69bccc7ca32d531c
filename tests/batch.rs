//! The span batcher, the span inserts of every arrangement and the run-time sizes against
//! per-pixel inserts: byte-identical framebuffers for random streams (both arithmetics,
//! MLAB and HT, pixel-major and span arrangements), the per-pixel inserts against the
//! reference side of each kind (`mlab_reference::kind`), and the pixel-major lanes resolve
//! against the scalar per-pixel resolve, bit for bit.

use mlab::framebuffer::Pixel;
use mlab::glam::{Vec3, Vec4};
use mlab::half::f16;
use mlab::{
    Background, DynFramebuffer, Fragment, Framebuffer, FramebufferError, Grid, HybridFramebuffer,
    HybridSpanFramebuffer, Layers, MlabFramebuffer, Paper, PixelMajor, Row, SpanBatcher, SpanFramebuffer, Spans,
    Unbiased, to_rgba8, to_rgba16f,
};
use mlab_reference::{HtKind, MlabKind, Model, RefKind, Rng};

/// More iterations in release (as BLAKE3's tests do).
const ROUNDS: usize = if cfg!(debug_assertions) { 6 } else { 40 };

/// What a pixel event pushes: a fragment, or an already quantized row.
#[derive(Clone, Copy, Debug)]
enum Item {
    Fragment(Fragment),
    Row(Row),
}

fn push<F: Framebuffer>(fb: &mut F, x: u32, y: u32, item: Item) {
    match item {
        Item::Fragment(f) => fb.insert(x, y, &f),
        Item::Row(r) => fb.insert_row(x, y, r),
    }
    .expect("inside");
}

fn push_batch<F: Framebuffer>(b: &mut SpanBatcher<'_, F>, x: u32, y: u32, item: Item) {
    match item {
        Item::Fragment(f) => b.insert(x, y, &f),
        Item::Row(r) => b.insert_row(x, y, r),
    }
    .expect("inside");
}

/// A stream of `(x, y, item)`: patches scanned line by line (as a rasterizer emits them),
/// single random pixels, and repeats of one pixel, with depths that tie on purpose, faint
/// fragments (the dithered quantization of [`Unbiased`]), half of the fragments keyed, and some rows of arbitrary bytes
/// (NaN depths and NaN bit patterns included) pushed as rows.
fn stream(rng: &mut Rng, w: u32, h: u32, n: usize) -> Vec<(u32, u32, Item)> {
    let mut out = Vec::new();
    while out.len() < n {
        let item = |rng: &mut Rng| {
            if rng.below(16) == 0 {
                return Item::Row(Row::from_bytes(rng.next_u64().to_le_bytes()));
            }
            let z = if rng.below(4) == 0 { 1.0 } else { 10.0 * rng.unit() };
            let alpha = if rng.below(4) == 0 {
                rng.unit() * 0.07
            } else {
                rng.unit()
            };
            let color = Vec3::new(rng.unit(), rng.unit(), rng.unit());
            let f = Fragment::straight(color, alpha, z).expect("valid");
            // Half the fragments carry a stable key (the dithers' seed, issue 30).
            Item::Fragment(if rng.below(2) == 0 {
                f.with_key(rng.next_u64() as u32)
            } else {
                f
            })
        };
        match rng.below(3) {
            0 => {
                let (x0, y0) = (rng.below(w as u64) as u32, rng.below(h as u64) as u32);
                let (pw, ph) = (1 + rng.below(20) as u32, 1 + rng.below(6) as u32);
                for y in y0..(y0 + ph).min(h) {
                    for x in x0..(x0 + pw).min(w) {
                        out.push((x, y, item(rng)));
                    }
                }
            }
            1 => out.push((rng.below(w as u64) as u32, rng.below(h as u64) as u32, item(rng))),
            _ => {
                let (x, y) = (rng.below(w as u64) as u32, rng.below(h as u64) as u32);
                for _ in 0..1 + rng.below(5) {
                    out.push((x, y, item(rng)));
                }
            }
        }
    }
    out
}

/// Per-pixel inserts into `reference`, the batcher into `batched`: every pixel resolves
/// bit-identically, and every whole-framebuffer resolve of both is bit-identical to the
/// scalar per-pixel resolve.
fn check<R: Framebuffer, B: Framebuffer<Arith = R::Arith>>(reference: &mut R, batched: &mut B, s: &[(u32, u32, Item)]) {
    reference.clear();
    batched.clear();
    for &(x, y, item) in s {
        push(reference, x, y, item);
    }
    let mut batch = SpanBatcher::new(batched);
    for &(x, y, item) in s {
        push_batch(&mut batch, x, y, item);
    }
    batch.finish().expect("flush");
    same_pixels(reference, batched);
    check_resolves(reference);
    check_resolves(batched);
}

/// Per-pixel inserts into both framebuffers (two arrangements): every pixel resolves
/// bit-identically (the span framebuffers' scalar `insert_row` against the pixel-major one).
fn check_per_pixel<R: Framebuffer, B: Framebuffer<Arith = R::Arith>>(
    reference: &mut R,
    other: &mut B,
    s: &[(u32, u32, Item)],
) {
    reference.clear();
    other.clear();
    for &(x, y, item) in s {
        push(reference, x, y, item);
        push(other, x, y, item);
    }
    same_pixels(reference, other);
}

/// Every pixel of `a` and `b` resolves bit for bit the same (NaN-safe: arbitrary rows may
/// resolve to anything finite).
fn same_pixels<R: Framebuffer, B: Framebuffer>(a: &R, b: &B) {
    for y in 0..a.height() {
        for x in 0..a.width() {
            let (p, q) = (a.resolve(x, y).expect("inside"), b.resolve(x, y).expect("inside"));
            assert_eq!(
                (p.color.to_array().map(f32::to_bits), p.transmittance.to_bits()),
                (q.color.to_array().map(f32::to_bits), q.transmittance.to_bits()),
                "pixel ({x}, {y})"
            );
        }
    }
}

/// Every whole-framebuffer resolve against [`Framebuffer::resolve`] per pixel, exactly.
fn check_resolves<F: Framebuffer>(fb: &F) {
    let (w, h) = (fb.width(), fb.height());
    let n = (w * h) as usize;
    for bg in [Background::Opaque(Vec3::new(0.25, 0.5, 1.0)), Background::Transparent] {
        let expect: Vec<Vec4> = (0..n as u32)
            .map(|i| fb.resolve(i % w, i / w).expect("inside").pixel(bg))
            .collect();
        let mut f32s = vec![Vec4::ZERO; n];
        fb.resolve_into(&mut f32s, bg).expect("size");
        assert_eq!(f32s, expect);
        let mut rgba8 = vec![[0u8; 4]; n];
        fb.resolve_rgba8(&mut rgba8, bg).expect("size");
        let f32_rgba8: Vec<[u8; 4]> = expect.iter().map(|&p| to_rgba8(p)).collect();
        {
            // RGBA8 is the integer resolve, MLAB's and HT's (tests/resolve.rs checks it
            // against the reference formulas): span by span the same bytes, and on these
            // streams (fragments, not arbitrary bytes) within one step of the f32 resolve's.
            for (i, (a, b)) in rgba8.iter().zip(&f32_rgba8).enumerate() {
                let (x, y) = (i as u32 % w, i as u32 / w);
                assert_eq!(*a, fb.resolve_span_rgba8(x / 8, y, bg)[x as usize % 8], "({x}, {y})");
                assert!(
                    a.iter().zip(b).all(|(p, q)| p.abs_diff(*q) <= 1),
                    "({x}, {y}): {a:?} vs {b:?}"
                );
            }
        }
        let mut rgba16 = vec![[f16::ZERO; 4]; n];
        fb.resolve_rgba16f(&mut rgba16, bg).expect("size");
        let e16: Vec<_> = expect.iter().map(|&p| to_rgba16f(p)).collect();
        assert_eq!(
            rgba16.iter().map(|p| p.map(f16::to_bits)).collect::<Vec<_>>(),
            e16.iter().map(|p| p.map(f16::to_bits)).collect::<Vec<_>>()
        );
    }
}

/// The storage of a pixel-major framebuffer after the stream `s`, pixel by pixel against the
/// reference side of its kind (`mlab_reference::kind`): the reference quantization and
/// Listing 1 or 2 of every item, from an empty pixel.
fn check_reference<K: RefKind>(storage: &[Row], w: u32, s: &[(u32, u32, Item)]) {
    let mut model = vec![Row::EMPTY; storage.len()];
    model.chunks_exact_mut(K::SLOTS).for_each(K::cleared);
    for &(x, y, item) in s {
        let p = y * w + x;
        let slots = &mut model[p as usize * K::SLOTS..][..K::SLOTS];
        match item {
            Item::Fragment(f) => K::ref_insert_fragment(slots, &f, p),
            Item::Row(r) => K::ref_insert_row(slots, r, p),
        }
    }
    for (p, (got, want)) in storage
        .chunks_exact(K::SLOTS)
        .zip(model.chunks_exact(K::SLOTS))
        .enumerate()
    {
        assert_eq!(
            got,
            want,
            "pixel ({}, {}): the per-pixel inserts against the reference",
            p as u32 % w,
            p as u32 / w
        );
    }
}

/// One kind in both arrangements: the batcher into the span framebuffer and into a second
/// pixel-major one against per-pixel inserts (see [`check`]), both pixel-major storages
/// byte-identical, the span framebuffer's per-pixel inserts against the pixel-major ones', and
/// the storage against the reference ([`check_reference`]).
fn run_kind<K: RefKind>(w: u32, h: u32, s: &[(u32, u32, Item)]) {
    let rows = Grid::<K::P, PixelMajor>::rows_needed(w, h).expect("size");
    let mut a = vec![Row::EMPTY; rows];
    let mut b = vec![Row::EMPTY; Grid::<K::P, Spans>::rows_needed(w, h).expect("size")];
    let mut c = vec![Row::EMPTY; rows];
    let mut reference = Grid::<K::P, PixelMajor>::new(&mut a, w, h).expect("size");
    check(
        &mut reference,
        &mut Grid::<K::P, Spans>::new(&mut b, w, h).expect("size"),
        s,
    );
    check(
        &mut reference,
        &mut Grid::<K::P, PixelMajor>::new(&mut c, w, h).expect("size"),
        s,
    );
    assert_eq!(a, c, "pixel-major span inserts, {:?}", K::P::LAYERS);
    check_per_pixel(
        &mut Grid::<K::P, PixelMajor>::new(&mut a, w, h).expect("size"),
        &mut Grid::<K::P, Spans>::new(&mut b, w, h).expect("size"),
        s,
    );
    check_reference::<K>(&a, w, s);
}

fn run<A: Model>() {
    let mut rng = Rng(0x1234_5678_9abc_def1 ^ A::NAME.len() as u64);
    for round in 0..ROUNDS {
        // Widths that are and are not multiples of 8, and that exceed the batcher's window.
        let (w, h) = [(8, 1), (13, 5), (67, 11), (130, 17), (3, 40)][round % 5];
        let s = stream(&mut rng, w, h, 200 + 300 * (round % 4));
        run_kind::<MlabKind<4, A>>(w, h, &s);
        run_kind::<HtKind<2, A>>(w, h, &s);

        // M = 1 and K = 1 too (the smallest arrays merge on every second fragment).
        let mut a = vec![Row::EMPTY; (w * h) as usize];
        let mut b = vec![Row::EMPTY; (w * h) as usize];
        check(
            &mut MlabFramebuffer::<1, A>::new(&mut a, w, h).expect("size"),
            &mut MlabFramebuffer::<1, A>::new(&mut b, w, h).expect("size"),
            &s,
        );
        assert_eq!(a, b);
        check_reference::<MlabKind<1, A>>(&a, w, &s);
    }
}

#[test]
fn batcher_is_byte_identical_to_per_pixel_inserts_unbiased() {
    run::<Unbiased>();
}

#[test]
fn batcher_is_byte_identical_to_per_pixel_inserts_paper() {
    run::<Paper>();
}

/// The stored bytes too, not only the resolves: span storage to pixel-major.
#[test]
fn batched_span_storage_equals_pixel_major_bytes() {
    let mut rng = Rng(77);
    let (w, h) = (45, 9);
    let s = stream(&mut rng, w, h, 2000);
    let mut a = vec![Row::EMPTY; (w * h * 3) as usize];
    let mut fa = MlabFramebuffer::<3>::new_cleared(&mut a, w, h).expect("size");
    for &(x, y, item) in &s {
        push(&mut fa, x, y, item);
    }
    let mut b = vec![Row::EMPTY; SpanFramebuffer::<3>::rows_needed(w, h).expect("size")];
    let mut fb = SpanFramebuffer::<3>::new_cleared(&mut b, w, h).expect("size");
    {
        let mut batch = SpanBatcher::new(&mut fb);
        for &(x, y, item) in &s {
            push_batch(&mut batch, x, y, item);
        }
        assert!(batch.pending() > 0);
        // Dropped without finish: the pending fragments are flushed by drop.
    }
    let mut back = vec![Row::EMPTY; (w * h * 3) as usize];
    MlabFramebuffer::<3>::new(&mut back, w, h)
        .expect("size")
        .copy_from(&fb)
        .expect("size");
    assert_eq!(back, a);
}

/// Its size and the span inserts it sent: 8 fragments of one span are one insert, a second
/// fragment for a pending pixel flushes the span first, a fragment of another span in the
/// same slot too.
#[test]
fn batcher_counts_its_span_inserts() {
    let mut storage = vec![Row::EMPTY; SpanFramebuffer::<2>::rows_needed(200, 40).expect("size")];
    let mut fb = SpanFramebuffer::<2>::new_cleared(&mut storage, 200, 40).expect("size");
    let mut batch = SpanBatcher::new(&mut fb);
    assert_eq!((batch.width(), batch.height()), (200, 40));
    let row = Row::new([1, 2, 3], 100, 1.0);
    for x in 0..8 {
        batch.insert_row(x, 0, row).expect("inside");
    }
    assert_eq!((batch.span_inserts(), batch.pending()), (0, 8));
    batch.insert_row(3, 0, row).expect("inside"); // pixel 3 is pending: its span goes first
    assert_eq!((batch.span_inserts(), batch.pending()), (1, 1));
    batch.insert_row(64, 0, row).expect("inside"); // another span, the same slot
    assert_eq!((batch.span_inserts(), batch.pending()), (2, 1));
    batch.flush().expect("flush");
    assert_eq!((batch.span_inserts(), batch.pending()), (3, 0));
}

#[test]
fn batcher_refuses_pixels_outside_and_keeps_nothing() {
    let mut storage = vec![Row::EMPTY; SpanFramebuffer::<2>::rows_needed(10, 3).expect("size")];
    let mut fb = SpanFramebuffer::<2>::new_cleared(&mut storage, 10, 3).expect("size");
    let mut batch = SpanBatcher::new(&mut fb);
    let row = Row::new([1, 2, 3], 100, 1.0);
    assert!(matches!(
        batch.insert_row(10, 0, row),
        Err(FramebufferError::OutOfBounds { x: 10, y: 0, .. })
    ));
    assert!(batch.insert_row(0, 3, row).is_err());
    assert!(batch.insert_row(u32::MAX, u32::MAX, row).is_err());
    assert_eq!(batch.pending(), 0);
    batch.insert_row(9, 2, row).expect("inside");
    assert_eq!(batch.pending(), 1);
    let fb = batch.framebuffer().expect("flush");
    assert_eq!(fb.pixel(9, 2).expect("inside")[0], row);
}

/// Where span inserts do not pay (`Framebuffer::SPAN_INSERTS_PAY`, false only for the
/// pixel-major HT framebuffer) the batcher holds nothing back: each push is in the framebuffer
/// at once, out-of-bounds pixels refused as before; everywhere else pushes wait in the batcher.
#[test]
fn batcher_passes_fragments_through_where_span_inserts_do_not_pay() {
    const { assert!(!HybridFramebuffer::<'static, 3>::SPAN_INSERTS_PAY) };
    const { assert!(HybridSpanFramebuffer::<'static, 3>::SPAN_INSERTS_PAY) };
    const { assert!(MlabFramebuffer::<'static, 3>::SPAN_INSERTS_PAY) };
    let mut rng = Rng(78);
    let (w, h) = (21, 5);
    let s = stream(&mut rng, w, h, 300);
    let mut a = vec![Row::EMPTY; HybridFramebuffer::<3>::rows_needed(w, h).expect("size")];
    let mut fa = HybridFramebuffer::<3>::new_cleared(&mut a, w, h).expect("size");
    let mut b = vec![Row::EMPTY; HybridFramebuffer::<3>::rows_needed(w, h).expect("size")];
    let mut fb = HybridFramebuffer::<3>::new_cleared(&mut b, w, h).expect("size");
    let mut batch = SpanBatcher::new(&mut fb);
    for &(x, y, item) in &s {
        push(&mut fa, x, y, item);
        push_batch(&mut batch, x, y, item);
        assert_eq!(batch.pending(), 0);
    }
    assert_eq!(batch.span_inserts(), 0, "passed through: no span insert");
    assert!(matches!(
        batch.insert_row(w, 0, Row::new([1, 2, 3], 100, 1.0)),
        Err(FramebufferError::OutOfBounds { .. })
    ));
    batch.finish().expect("flush");
    assert_eq!(fb.as_bytes(), fa.as_bytes());
}

/// Every run-time size: byte-identical to the compile-time type on the same stream.
#[test]
fn dyn_framebuffer_matches_the_compile_time_types() {
    fn same<F: Framebuffer<Arith = Unbiased>>(layers: Layers, mut reference: F, s: &[(u32, u32, Item)]) {
        let (w, h) = (reference.width(), reference.height());
        let mut storage = vec![Row::EMPTY; layers.rows_needed(w, h).expect("size")];
        let mut fb: DynFramebuffer = DynFramebuffer::new_cleared(layers, &mut storage, w, h).expect("size");
        assert_eq!(fb.layers(), layers);
        reference.clear();
        let mut batch = SpanBatcher::new(&mut fb);
        for &(x, y, item) in s {
            push(&mut reference, x, y, item);
            push_batch(&mut batch, x, y, item);
        }
        batch.finish().expect("flush");
        assert_eq!(fb.as_bytes(), reference.as_bytes(), "{layers:?}");
        check_resolves(&fb);
        let heights: Vec<u32> = fb.bands_mut(4).map(|b| b.height()).collect();
        assert_eq!(heights.iter().sum::<u32>(), h);
    }
    let mut rng = Rng(5);
    let (w, h) = (21, 7);
    let s = stream(&mut rng, w, h, 800);
    macro_rules! sizes {
        ($($n:literal)*) => {$(
            let mut st = vec![Row::EMPTY; SpanFramebuffer::<$n>::rows_needed(w, h).expect("size")];
            same(Layers::Mlab($n), SpanFramebuffer::<$n>::new(&mut st, w, h).expect("size"), &s);
            let mut st = vec![Row::EMPTY; HybridSpanFramebuffer::<$n>::rows_needed(w, h).expect("size")];
            same(Layers::Hybrid($n), HybridSpanFramebuffer::<$n>::new(&mut st, w, h).expect("size"), &s);
        )*};
    }
    sizes!(1 2 3 4 5 6 7 8);
    for bad in [0, 9, 100] {
        assert_eq!(
            Layers::Mlab(bad).rows_needed(8, 8),
            Err(FramebufferError::UnsupportedLayers { rows: bad })
        );
        let mut st = vec![Row::EMPTY; 64];
        assert!(DynFramebuffer::<Unbiased>::new(Layers::Hybrid(bad), &mut st, 8, 8).is_err());
    }
}

/// Bands of the pixel-major framebuffers cover the lines in order.
#[test]
fn pixel_major_bands_split_the_storage() {
    let (w, h) = (5, 7);
    let mut storage = vec![Row::EMPTY; (w * h * 2) as usize];
    let mut fb = HybridFramebuffer::<1>::new_cleared(&mut storage, w, h).expect("size");
    for (b, mut band) in fb.bands_mut(3).enumerate() {
        assert_eq!(band.height(), if b == 2 { 1 } else { 3 });
        band.insert_row(4, 0, Row::new([b as u8, 0, 0], 0, 1.0))
            .expect("inside");
    }
    assert_eq!(fb.bands_mut(0).count(), 0);
    for b in 0..3u32 {
        assert_eq!(
            fb.pixel(4, 3 * b).expect("inside").0[0],
            Row::new([b as u8, 0, 0], 0, 1.0)
        );
    }
}

/// The batcher's size as the docs state it (src/lib.rs, src/batch.rs: "about 52 KiB"): 256
/// pending spans of five f32 lanes and their fragment keys, their masks and span keys.
#[test]
fn batcher_size_is_as_documented() {
    let size = std::mem::size_of::<SpanBatcher<'static, SpanFramebuffer<'static, 4>>>();
    assert!((51 * 1024..=53 * 1024).contains(&size), "{size} bytes");
}
