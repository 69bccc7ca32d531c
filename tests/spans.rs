//! Span framebuffers (layer-major, lanes) against the pixel-major framebuffers (scalar),
//! byte for byte: unaligned spans, partial spans at the right edge, widths that are not a
//! multiple of 8, out-of-bounds lanes, bands, conversions.

mod common;

use mlab::Framebuffer;
use mlab::framebuffer::Pixel;
use mlab::glam::{Vec3, Vec4};
use mlab::half::f16;
use mlab::lanes::{FragmentLanes, LANES};
use mlab::{
    Background, FramebufferError, Grid, Ht, HybridFramebuffer, HybridSpanFramebuffer, Mlab, PixelMajor, Row,
    SpanFramebuffer, Spans, Unbiased,
};
use mlab_reference::{HtKind, MlabKind, RefKind};
use proptest::prelude::*;

const BG: Background = Background::Opaque(Vec3::new(0.1, 0.2, 0.3));

/// A span operation: lane-0 pixel, rows, mask (clipped to the framebuffer by the generator).
type Op = (u32, u32, [Row; LANES], u8);

fn ops(width: u32, height: u32) -> impl Strategy<Value = Vec<Op>> {
    let row = prop_oneof![
        4 => common::normal_fragment().prop_map(|f| <mlab::Paper as mlab::Arithmetic>::quantize(&f, 0)),
        1 => any::<u64>().prop_map(|b| Row::from_bytes(b.to_le_bytes())),
    ];
    prop::collection::vec((0..width, 0..height, prop::array::uniform8(row), any::<u8>()), 0..60).prop_map(move |v| {
        v.into_iter()
            .map(|(x, y, rows, mask)| {
                // Keep only lanes inside the framebuffer.
                let inside = (0..LANES)
                    .filter(|&l| x + (l as u32) < width)
                    .fold(0u8, |m, l| m | 1 << l);
                (x, y, rows, mask & inside)
            })
            .collect()
    })
}

/// The pixels after `ops` by the reference side of the kind (`mlab_reference::kind`): each
/// on lane's row inserted by Listing 1 or 2 into the slots of its pixel, from empty pixels.
fn reference_pixels<K: RefKind>(w: u32, h: u32, ops: &[Op]) -> Vec<Row> {
    let mut model = vec![Row::EMPTY; (w * h) as usize * K::SLOTS];
    model.chunks_exact_mut(K::SLOTS).for_each(K::cleared);
    for &(x, y, rows, mask) in ops {
        for (l, row) in rows.iter().enumerate().filter(|&(l, _)| mask & (1 << l) != 0) {
            let p = y * w + x + l as u32;
            K::ref_insert_row(&mut model[p as usize * K::SLOTS..][..K::SLOTS], *row, p);
        }
    }
    model
}

/// One check for every kind of pixel: span inserts into a span grid against pixel inserts
/// into a pixel-major grid (scalar) and against the reference side of the kind, pixel for
/// pixel, byte for byte after conversion, padding lanes as cleared, every resolve bit for bit
/// (RGBA8 also against the reference integer resolve), and the round trip back into spans.
fn check<K: RefKind>(w: u32, h: u32, ops: &[Op]) -> Result<(), TestCaseError> {
    type P<K> = <K as RefKind>::P;
    let mut span_storage = vec![Row::EMPTY; Grid::<P<K>, Spans>::rows_needed(w, h).unwrap()];
    let mut fb = Grid::<P<K>, Spans>::new_cleared(&mut span_storage, w, h).unwrap();
    let mut px_storage = vec![Row::EMPTY; Grid::<P<K>, PixelMajor>::rows_needed(w, h).unwrap()];
    let mut reference = Grid::<P<K>, PixelMajor>::new_cleared(&mut px_storage, w, h).unwrap();
    for &(x, y, rows, mask) in ops {
        fb.insert_span(x, y, &rows, mask).unwrap();
        for (l, row) in rows.iter().enumerate() {
            if mask & (1 << l) != 0 {
                reference.insert_row(x + l as u32, y, *row).unwrap();
            }
        }
    }
    let model = reference_pixels::<K>(w, h, ops);
    let slots = |x: u32, y: u32| &model[(y * w + x) as usize * K::SLOTS..][..K::SLOTS];
    for y in 0..h {
        for x in 0..w {
            prop_assert_eq!(
                fb.pixel(x, y).unwrap(),
                reference.pixel(x, y).unwrap(),
                "{:?} ({}, {})",
                P::<K>::LAYERS,
                x,
                y
            );
            prop_assert_eq!(
                K::slots(fb.pixel(x, y).unwrap()),
                slots(x, y),
                "reference ({}, {})",
                x,
                y
            );
        }
    }
    let mut converted = vec![Row::EMPTY; reference.as_rows().len()];
    let mut conv = Grid::<P<K>, PixelMajor>::new(&mut converted, w, h).unwrap();
    conv.copy_from(&fb).unwrap();
    prop_assert_eq!(
        conv.as_rows(),
        reference.as_rows(),
        "w={} h={} {:?}",
        w,
        h,
        P::<K>::LAYERS
    );
    // Padding lanes stay as cleared.
    let mut blank_storage = span_storage_clone_len::<P<K>>(w, h);
    let blank = Grid::<P<K>, Spans>::new_cleared(&mut blank_storage, w, h).unwrap();
    let r = K::SLOTS;
    for y in 0..h {
        for x in w..w.div_ceil(8) * 8 {
            let i = ((y as usize * w.div_ceil(8) as usize + x as usize / 8) * r) * 8 + x as usize % 8;
            for j in 0..r {
                prop_assert_eq!(fb.as_rows()[i + j * 8], blank.as_rows()[i + j * 8]);
            }
        }
    }
    // Resolves equal bit for bit.
    let n = (w * h) as usize;
    let (mut a, mut b) = (vec![[0u8; 4]; n], vec![[0u8; 4]; n]);
    fb.resolve_rgba8(&mut a, BG).unwrap();
    reference.resolve_rgba8(&mut b, BG).unwrap();
    prop_assert_eq!(&a, &b);
    for (i, px) in a.iter().enumerate() {
        prop_assert_eq!(*px, K::ref_rgba8(slots(i as u32 % w, i as u32 / w), BG));
    }
    let (mut a, mut b) = (vec![Vec4::ZERO; n], vec![Vec4::ZERO; n]);
    fb.resolve_into(&mut a, Background::Transparent).unwrap();
    reference.resolve_into(&mut b, Background::Transparent).unwrap();
    prop_assert_eq!(bits(&a), bits(&b));
    let (mut a, mut b) = (vec![[f16::ZERO; 4]; n], vec![[f16::ZERO; 4]; n]);
    fb.resolve_rgba16f(&mut a, BG).unwrap();
    reference.resolve_rgba16f(&mut b, BG).unwrap();
    prop_assert_eq!(
        a.iter().map(|p| p.map(f16::to_bits)).collect::<Vec<_>>(),
        b.iter().map(|p| p.map(f16::to_bits)).collect::<Vec<_>>()
    );
    // Round trip through the pixel-major arrangement.
    let mut again = span_storage_clone_len::<P<K>>(w, h);
    let mut fb2 = Grid::<P<K>, Spans>::new_cleared(&mut again, w, h).unwrap();
    fb2.copy_from(&conv).unwrap();
    prop_assert_eq!(fb2.as_rows(), fb.as_rows());
    Ok(())
}

/// [`bands_equal_whole`] for one kind of pixel.
fn bands_equal_whole_for<P: Pixel>(w: u32, h: u32, ops: &[Op], lines: u32) -> Result<(), TestCaseError> {
    let mut whole = vec![Row::EMPTY; Grid::<P, Spans>::rows_needed(w, h).unwrap()];
    let mut banded = whole.clone();
    let mut fb = Grid::<P, Spans>::new_cleared(&mut whole, w, h).unwrap();
    let mut fb2 = Grid::<P, Spans>::new_cleared(&mut banded, w, h).unwrap();
    for &(x, y, rows, mask) in ops {
        fb.insert_span(x, y, &rows, mask).unwrap();
    }
    let mut bands: Vec<_> = fb2.bands_mut(lines).collect();
    prop_assert_eq!(bands.len() as u32, h.div_ceil(lines));
    for &(x, y, rows, mask) in ops {
        bands[(y / lines) as usize]
            .insert_span(x, y % lines, &rows, mask)
            .unwrap();
    }
    drop(bands);
    prop_assert_eq!(fb.as_rows(), fb2.as_rows());
    Ok(())
}

fn span_storage_clone_len<P: Pixel>(w: u32, h: u32) -> Vec<Row> {
    vec![Row::EMPTY; Grid::<P, Spans>::rows_needed(w, h).unwrap()]
}

fn bits(v: &[Vec4]) -> Vec<[u32; 4]> {
    v.iter().map(|p| p.to_array().map(f32::to_bits)).collect()
}

fn size() -> impl Strategy<Value = (u32, u32)> {
    (prop::sample::select(vec![1u32, 7, 8, 9, 13, 16, 17]), 1u32..4)
}

proptest! {
    #[test]
    fn span_framebuffers_equal_pixel_major_scalar(((w, h), ops) in size().prop_flat_map(|(w, h)| (Just((w, h)), ops(w, h)))) {
        check::<MlabKind<1, Unbiased>>(w, h, &ops)?;
        check::<MlabKind<4, Unbiased>>(w, h, &ops)?;
        check::<HtKind<1, Unbiased>>(w, h, &ops)?;
        check::<HtKind<3, Unbiased>>(w, h, &ops)?;
        // 9 slots a pixel, the widest: `gather`'s whole-span transpose at its largest size.
        check::<HtKind<8, Unbiased>>(w, h, &ops)?;
    }

    /// Inserting through bands (one per thread) gives the same storage as inserting into the whole.
    #[test]
    fn bands_equal_whole(((w, h), ops) in (prop::sample::select(vec![5u32, 8, 13]), 1u32..9).prop_flat_map(|(w, h)| (Just((w, h)), ops(w, h))), lines in 1u32..4) {
        bands_equal_whole_for::<Mlab<2>>(w, h, &ops, lines)?;
        bands_equal_whole_for::<Ht<1>>(w, h, &ops, lines)?;
    }
}

#[test]
fn out_of_bounds_lanes_are_refused_and_change_nothing() {
    let (w, h) = (13u32, 2u32);
    let mut s = vec![Row::EMPTY; SpanFramebuffer::<2>::rows_needed(w, h).unwrap()];
    let mut fb = SpanFramebuffer::<2>::new_cleared(&mut s, w, h).unwrap();
    let rows = [Row::new([1, 2, 3], 100, 1.0); 8];
    // x = 9: lanes 0..4 are pixels 9..12 (in), lane 4 is pixel 13 (out).
    assert_eq!(
        fb.insert_span(9, 0, &rows, 0b1_1111),
        Err(FramebufferError::OutOfBounds {
            x: 13,
            y: 0,
            width: 13,
            height: 2
        })
    );
    assert_eq!(
        fb.insert_span(0, 2, &rows, 1),
        Err(FramebufferError::OutOfBounds {
            x: 0,
            y: 2,
            width: 13,
            height: 2
        })
    );
    assert_eq!(
        fb.insert_span(u32::MAX, 0, &rows, 0x80),
        Err(FramebufferError::OutOfBounds {
            x: u32::MAX,
            y: 0,
            width: 13,
            height: 2
        })
    );
    assert!(fb.as_rows().iter().all(|r| r.is_empty()));
    // A zero mask is fine anywhere on a valid line, and changes nothing.
    fb.insert_span(u32::MAX, 1, &rows, 0).unwrap();
    fb.insert_span(9, 0, &rows, 0b1111).unwrap();
    assert_eq!(fb.pixel(12, 0).unwrap()[0], rows[0]);
    // Invalid fragments: reported, untouched; coordinates checked first.
    let mut frags = FragmentLanes {
        color: [[0.5; 8]; 3],
        alpha: [0.5; 8],
        depth: [2.0; 8],
        key: None,
    };
    frags.depth[1] = f32::INFINITY;
    frags.alpha[2] = 2.0;
    assert_eq!(
        fb.insert_span_fragments(0, 1, &frags, 0xff),
        Ok(mlab::InvalidLanes(0b110))
    );
    assert!(fb.pixel(1, 1).unwrap()[0].is_empty());
    assert!(!fb.pixel(0, 1).unwrap()[0].is_empty());
    assert!(fb.insert_span_fragments(8, 1, &frags, 0xff).is_err());
    // Wrong storage and output sizes.
    let mut short = vec![Row::EMPTY; 3];
    assert!(matches!(
        SpanFramebuffer::<2>::new(&mut short, w, h),
        Err(FramebufferError::StorageLength { .. })
    ));
    assert!(matches!(
        HybridSpanFramebuffer::<2>::new(&mut short, w, h),
        Err(FramebufferError::StorageLength { .. })
    ));
    assert_eq!(
        SpanFramebuffer::<2>::rows_needed(u32::MAX, u32::MAX),
        Err(FramebufferError::SizeOverflow)
    );
    let mut out = vec![[0u8; 4]; 5];
    assert!(matches!(
        fb.resolve_rgba8(&mut out, BG),
        Err(FramebufferError::OutputLength {
            expected: 26,
            actual: 5
        })
    ));
}

#[test]
fn hybrid_new_over_empty_rows_needs_clearing() {
    // The trap reported by the lab: Row::EMPTY bytes are not an empty tail.
    let mut s = vec![Row::EMPTY; HybridFramebuffer::<1>::rows_needed(1, 1).unwrap()];
    let fb = HybridFramebuffer::<1>::new(&mut s, 1, 1).unwrap();
    assert_ne!(fb.resolve(0, 0).unwrap(), mlab::Resolved::CLEAR);
    let fb = HybridFramebuffer::<1>::new_cleared(&mut s, 1, 1).unwrap();
    assert_eq!(fb.resolve(0, 0).unwrap(), mlab::Resolved::CLEAR);
}

/// A band rebuilt from its own rows with `Grid::with_first_pixel` (as the C API's
/// `mlab_framebuffer_band` does) inserts the bytes of the band `split_lines` gives, and of the
/// whole framebuffer: keyed and content-keyed faint fragments (dithered), per pixel and in
/// spans, MLAB and HT, both layouts; without the first pixel id the dithers differ.
#[test]
fn a_band_rebuilt_with_its_first_pixel_inserts_the_whole_framebuffers_bytes() {
    fn check<P: Pixel, L: mlab::framebuffer::Arrangement>() {
        let (w, h, split) = (13u32, 5u32, 3u32);
        let frags: Vec<(u32, u32, mlab::Fragment)> = (0..400u32)
            .map(|i| {
                let a = 0.01 + (i % 7) as f32 * 0.003;
                let f = mlab::Fragment::straight(Vec3::new(0.9, 0.5, 0.2), a, 1.0 + (i % 11) as f32).unwrap();
                let f = if i % 3 == 0 { f } else { f.with_key(i / 4) };
                (i * 7 % w, i * 3 % h, f)
            })
            .collect();
        let lanes = FragmentLanes {
            color: [[0.3; 8], [0.2; 8], [0.1; 8]],
            alpha: [0.02, 0.03, 0.01, 0.02, 0.015, 0.025, 0.01, 0.03],
            depth: [0.5; 8],
            key: Some([1, 2, 3, 4, 5, 6, 7, 8]),
        };
        let rows = Grid::<P, L>::rows_needed(w, h).unwrap();
        let (mut whole, mut split_rows, mut rebuilt) =
            (vec![Row::EMPTY; rows], vec![Row::EMPTY; rows], vec![Row::EMPTY; rows]);
        let mut fb = Grid::<P, L>::new_cleared(&mut whole, w, h).unwrap();
        let (mut top, mut bottom) = Grid::<P, L>::new_cleared(&mut split_rows, w, h)
            .unwrap()
            .split_lines(split);
        let at = Grid::<P, L>::rows_needed(w, split).unwrap();
        let (a, b) = rebuilt.split_at_mut(at);
        let mut rtop = Grid::<P, L>::new_cleared(a, w, split).unwrap();
        let mut rbottom = Grid::<P, L>::new_cleared(b, w, h - split)
            .unwrap()
            .with_first_pixel(split * w);
        assert_eq!(rbottom.first_pixel(), bottom.first_pixel());
        for &(x, y, f) in &frags {
            fb.insert(x, y, &f).unwrap();
            let (s, r, y) = if y < split {
                (&mut top, &mut rtop, y)
            } else {
                (&mut bottom, &mut rbottom, y - split)
            };
            s.insert(x, y, &f).unwrap();
            r.insert(x, y, &f).unwrap();
        }
        assert_eq!(fb.insert_span_straight(4, 4, &lanes, 0xff).unwrap().0, 0);
        assert_eq!(bottom.insert_span_straight(4, 4 - split, &lanes, 0xff).unwrap().0, 0);
        assert_eq!(rbottom.insert_span_straight(4, 4 - split, &lanes, 0xff).unwrap().0, 0);
        assert_eq!(split_rows, whole);
        assert_eq!(rebuilt, whole);
        // The same band from its rows without the first pixel id: other dithers.
        let mut other = vec![Row::EMPTY; rows - at];
        let mut band = Grid::<P, L>::new_cleared(&mut other, w, h - split).unwrap();
        for &(x, y, f) in frags.iter().filter(|&&(_, y, _)| y >= split) {
            band.insert(x, y - split, &f).unwrap();
        }
        assert_ne!(other[..], whole[at..]);
    }
    check::<Mlab<4>, Spans>();
    check::<Ht<2>, Spans>();
    check::<Mlab<3>, PixelMajor>();
    check::<Ht<1>, PixelMajor>();
}

/// `copy_from` defines the whole storage: into a grid made with `new` over storage that held
/// anything (here `Row::EMPTY`, which is not an empty HT tail, and arbitrary bytes), the rows
/// are those of `new_cleared` then `copy_from` (13 x 2: padding lanes in every span line).
#[test]
fn copy_from_writes_the_padding_as_cleared() {
    fn check<P: Pixel>(fill: Row) {
        let (w, h) = (13, 2);
        let mut a = vec![Row::EMPTY; Grid::<P, PixelMajor>::rows_needed(w, h).unwrap()];
        let mut src = Grid::<P, PixelMajor>::new_cleared(&mut a, w, h).unwrap();
        for i in 0..20u32 {
            src.insert_row(i * 7 % w, i % h, Row::new([i as u8, 3, 9], 100 + i as u8, i as f32))
                .unwrap();
        }
        let n = Grid::<P, Spans>::rows_needed(w, h).unwrap();
        let (mut b, mut c) = (vec![fill; n], vec![Row::EMPTY; n]);
        let mut kept = Grid::<P, Spans>::new(&mut b, w, h).unwrap();
        kept.copy_from(&src).unwrap();
        let mut cleared = Grid::<P, Spans>::new_cleared(&mut c, w, h).unwrap();
        cleared.copy_from(&src).unwrap();
        assert_eq!(kept.as_rows(), cleared.as_rows(), "{:?}", P::LAYERS);
        // And back: pixel-major storage over anything.
        let mut d = vec![fill; a_len::<P>(w, h)];
        let mut back = Grid::<P, PixelMajor>::new(&mut d, w, h).unwrap();
        back.copy_from(&kept).unwrap();
        assert_eq!(back.as_rows(), src.as_rows(), "{:?}", P::LAYERS);
    }
    fn a_len<P: Pixel>(w: u32, h: u32) -> usize {
        Grid::<P, PixelMajor>::rows_needed(w, h).unwrap()
    }
    for fill in [Row::EMPTY, Row::from_bytes([0xab; 8])] {
        check::<Ht<3>>(fill);
        check::<Ht<1, mlab::Paper>>(fill);
        check::<Mlab<2>>(fill);
    }
}

/// `DynFramebuffer` has the `Grid` reads and copies: `pixel`, `copy_from`, `saturated_pixels`.
#[test]
fn dyn_framebuffer_reads_and_copies_as_grid_does() {
    use mlab::{DynFramebuffer, Layers};
    let (w, h) = (13, 2);
    for layers in [Layers::Mlab(3), Layers::Hybrid(2)] {
        let n = layers.rows_needed(w, h).unwrap();
        let (mut a, mut b, mut c) = (
            vec![Row::EMPTY; n],
            vec![Row::from_bytes([0x5a; 8]); n],
            vec![Row::EMPTY; n],
        );
        let mut src: DynFramebuffer = DynFramebuffer::new_cleared(layers, &mut a, w, h).unwrap();
        let mut typed = HybridSpanFramebuffer::<2>::new_cleared(&mut c, w, h).unwrap();
        for i in 0..30u32 {
            let row = Row::new([i as u8, 3, 9], 10 + i as u8, i as f32);
            src.insert_row(i * 5 % w, i % h, row).unwrap();
            typed.insert_row(i * 5 % w, i % h, row).unwrap();
        }
        let mut dst: DynFramebuffer = DynFramebuffer::new(layers, &mut b, w, h).unwrap();
        dst.copy_from(&src).unwrap();
        assert_eq!(dst.as_rows(), src.as_rows());
        assert_eq!(dst.saturated_pixels(), 0);
        let px = dst.pixel(12, 1).unwrap();
        assert_eq!(px.layers(), layers);
        if layers == Layers::Hybrid(2) {
            let (head, tail) = typed.pixel(12, 1).unwrap();
            assert_eq!(px.rows(), &head);
            assert_eq!(px.tail(), Some(tail));
        } else {
            assert_eq!(px.rows().len(), 3);
            assert_eq!(px.tail(), None);
        }
        assert!(dst.pixel(13, 0).is_err());
        let mut other = vec![Row::EMPTY; Layers::Mlab(1).rows_needed(w, h).unwrap()];
        let one: DynFramebuffer = DynFramebuffer::new_cleared(Layers::Mlab(1), &mut other, w, h).unwrap();
        assert_eq!(dst.copy_from(&one), Err(FramebufferError::SizeMismatch));
    }
}
