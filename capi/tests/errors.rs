//! Every bad input of the C API gets its documented status, and changes nothing: null and
//! misaligned pointers, an uninitialized struct, sizes 0, overflowing sizes, short and long
//! buffers, invalid fragments, pixels outside, enum values out of range.

use mlab::{Fragment, FragmentError};
use mlab_capi::*;
use std::mem::MaybeUninit;
use std::ptr::{null, null_mut};

const W: u32 = 13;
const H: u32 = 3;

struct CFb {
    storage: Vec<MlabRow>,
    fb: MlabFramebuffer,
}

fn c_fb(method: MlabMethod, layers: u32) -> CFb {
    let mut rows = 0;
    // SAFETY: a size_t to write.
    assert_eq!(
        unsafe { mlab_rows_needed(method, layers, W, H, &mut rows) },
        MlabStatus::Ok
    );
    let mut storage = vec![MlabRow { bytes: [0; 8] }; rows];
    let mut fb = MaybeUninit::uninit();
    // SAFETY: the storage lives in the returned value with the struct.
    let st = unsafe {
        mlab_framebuffer_init(
            fb.as_mut_ptr(),
            method,
            layers,
            MLAB_ARITHMETIC_UNBIASED,
            storage.as_mut_ptr(),
            rows,
            W,
            H,
        )
    };
    assert_eq!(st, MlabStatus::Ok);
    // SAFETY: init succeeded.
    CFb {
        storage,
        fb: unsafe { fb.assume_init() },
    }
}

impl CFb {
    fn bytes(&self) -> Vec<u8> {
        self.storage.iter().flat_map(|r| r.bytes).collect()
    }
}

const OPAQUE: MlabBackground = MlabBackground {
    kind: MLAB_BACKGROUND_OPAQUE,
    rgb: [1.0, 1.0, 1.0],
};

const SPAN: MlabFragmentSpan = MlabFragmentSpan {
    r: [0.5; 8],
    g: [0.5; 8],
    b: [0.5; 8],
    a: [0.5; 8],
    depth: [1.0; 8],
};

const SPAN_KEYED: MlabFragmentSpanKeyed = MlabFragmentSpanKeyed {
    r: [0.5; 8],
    g: [0.5; 8],
    b: [0.5; 8],
    a: [0.5; 8],
    depth: [1.0; 8],
    key: [7; 8],
};

/// Every function that takes a framebuffer, called with `fb`, returns `want`.
fn every_call_returns(fb: *mut MlabFramebuffer, want: MlabStatus, what: &str) {
    let mut out8 = vec![[0u8; 4]; (W * H) as usize];
    let mut out32 = vec![mlab::glam::Vec4::ZERO; (W * H) as usize];
    let mut out16 = vec![[0u16; 4]; (W * H) as usize];
    let n = (W * H) as usize;
    let frag = MlabPixelFragment {
        x: 0,
        y: 0,
        rgba: [0.5; 4],
        depth: 1.0,
    };
    let keyed = MlabPixelFragmentKeyed {
        x: 0,
        y: 0,
        rgba: [0.5; 4],
        depth: 1.0,
        key: 7,
    };
    let (mut refused, mut inserted, mut band) = (0u8, 0usize, MaybeUninit::uninit());
    // SAFETY: every other pointer is valid; `fb` is what is tested (null, misaligned,
    // uninitialized: each refused before it is used for anything but reading the struct).
    let got = unsafe {
        [
            mlab_framebuffer_clear(fb),
            mlab_framebuffer_band(fb, 0, 1, band.as_mut_ptr()),
            mlab_insert_straight(fb, 0, 0, 0.5, 0.5, 0.5, 0.5, 1.0),
            mlab_insert_premultiplied(fb, 0, 0, 0.5, 0.5, 0.5, 0.5, 1.0),
            mlab_insert_straight_keyed(fb, 0, 0, 0.5, 0.5, 0.5, 0.5, 1.0, 7),
            mlab_insert_premultiplied_keyed(fb, 0, 0, 0.5, 0.5, 0.5, 0.5, 1.0, 7),
            mlab_insert_span_straight(fb, 0, 0, &SPAN, 1, &mut refused),
            mlab_insert_span_premultiplied(fb, 0, 0, &SPAN, 1, &mut refused),
            mlab_insert_span_straight_keyed(fb, 0, 0, &SPAN_KEYED, 1, &mut refused),
            mlab_insert_span_premultiplied_keyed(fb, 0, 0, &SPAN_KEYED, 1, &mut refused),
            mlab_insert_batch_straight(fb, &frag, 1, &mut inserted),
            mlab_insert_batch_premultiplied(fb, &frag, 1, &mut inserted),
            mlab_insert_batch_straight_keyed(fb, &keyed, 1, &mut inserted),
            mlab_insert_batch_premultiplied_keyed(fb, &keyed, 1, &mut inserted),
            mlab_resolve_rgba8(fb, OPAQUE, out8.as_mut_ptr().cast(), n),
            mlab_resolve_f32(fb, OPAQUE, out32.as_mut_ptr().cast(), n),
            mlab_resolve_rgba16f(fb, OPAQUE, out16.as_mut_ptr().cast(), n),
        ]
    };
    assert_eq!(got, [want; 17], "{what}");
    assert_eq!((refused, inserted), (0, 0), "{what}: out-parameters untouched");
    assert!(out8.iter().all(|p| *p == [0; 4]), "{what}: output untouched");
}

#[test]
fn null_misaligned_and_uninitialized_framebuffers() {
    every_call_returns(null_mut(), MlabStatus::NullPointer, "null");
    // A struct one byte off its alignment, inside an aligned buffer.
    let mut buf = [0u64; 8];
    let misaligned = buf.as_mut_ptr().cast::<u8>().wrapping_add(1).cast::<MlabFramebuffer>();
    every_call_returns(misaligned, MlabStatus::Misaligned, "misaligned");
    // A zeroed struct (never initialized).
    let mut zeroed = MaybeUninit::<MlabFramebuffer>::zeroed();
    every_call_returns(zeroed.as_mut_ptr(), MlabStatus::NotInitialized, "zeroed");
    // A struct whose init failed is marked uninitialized, whatever it held before.
    let mut c = c_fb(MLAB_METHOD_MLAB, 2);
    let mut copy = c.fb;
    // SAFETY: valid pointers; the storage length is wrong on purpose.
    let st = unsafe {
        mlab_framebuffer_init(
            &mut copy,
            MLAB_METHOD_MLAB,
            2,
            0,
            c.storage.as_mut_ptr(),
            c.storage.len() - 1,
            W,
            H,
        )
    };
    assert_eq!(st, MlabStatus::StorageLength);
    every_call_returns(&mut copy, MlabStatus::NotInitialized, "failed init");
    // The original, a copy of the same view, still works.
    every_call_returns_ok(&mut c.fb);
}

fn every_call_returns_ok(fb: *mut MlabFramebuffer) {
    // SAFETY: an initialized framebuffer.
    assert_eq!(
        unsafe { mlab_insert_straight(fb, 1, 1, 0.5, 0.5, 0.5, 0.5, 1.0) },
        MlabStatus::Ok
    );
    // SAFETY: as above.
    assert_eq!(
        unsafe { mlab_insert_straight_keyed(fb, 1, 1, 0.5, 0.5, 0.5, 0.5, 1.0, 3) },
        MlabStatus::Ok
    );
}

#[test]
fn rows_needed_refuses_bad_sizes() {
    let rows = std::cell::Cell::new(12345usize);
    // SAFETY: `rows` is a size_t to write (or null, refused).
    unsafe {
        let f = |m, l, w, h| mlab_rows_needed(m, l, w, h, rows.as_ptr());
        assert_eq!(f(MLAB_METHOD_MLAB, 0, 8, 8), MlabStatus::UnsupportedLayers);
        assert_eq!(f(MLAB_METHOD_HYBRID, 9, 8, 8), MlabStatus::UnsupportedLayers);
        assert_eq!(f(2, 4, 8, 8), MlabStatus::InvalidArgument);
        assert_eq!(f(MLAB_METHOD_MLAB, 4, 0, 8), MlabStatus::ZeroSize);
        assert_eq!(f(MLAB_METHOD_MLAB, 4, 8, 0), MlabStatus::ZeroSize);
        assert_eq!(f(MLAB_METHOD_HYBRID, 8, u32::MAX, u32::MAX), MlabStatus::SizeOverflow);
        assert_eq!(rows.get(), 12345, "unchanged on error");
        assert_eq!(f(MLAB_METHOD_MLAB, 4, 13, 3), MlabStatus::Ok);
        assert_eq!(rows.get(), 16 * 3 * 4, "two 8-pixel spans a line, 4 rows a pixel");
        assert_eq!(f(MLAB_METHOD_HYBRID, 3, 13, 3), MlabStatus::Ok);
        assert_eq!(rows.get(), 16 * 3 * 4, "HT 3: 3 head rows and the tail");
        assert_eq!(
            mlab_rows_needed(MLAB_METHOD_MLAB, 4, 8, 8, null_mut()),
            MlabStatus::NullPointer
        );
        let mut buf = [0u64; 2];
        let misaligned = buf.as_mut_ptr().cast::<u8>().wrapping_add(4).cast::<usize>();
        assert_eq!(
            mlab_rows_needed(MLAB_METHOD_MLAB, 4, 8, 8, misaligned),
            MlabStatus::Misaligned
        );
    }
}

#[test]
fn init_refuses_bad_storage_and_arguments() {
    let mut rows = 0;
    // SAFETY: a size_t to write.
    assert_eq!(
        unsafe { mlab_rows_needed(MLAB_METHOD_MLAB, 4, W, H, &mut rows) },
        MlabStatus::Ok
    );
    let mut storage = vec![MlabRow { bytes: [7; 8] }; rows + 1];
    let p = storage.as_mut_ptr();
    let mut fb = MaybeUninit::uninit();
    let init = |fb: *mut MlabFramebuffer, m, l, a, s: *mut MlabRow, n, w, h| {
        // SAFETY: `s` is null, misaligned (refused) or valid for `n <= rows + 1` rows.
        unsafe { mlab_framebuffer_init(fb, m, l, a, s, n, w, h) }
    };
    let f = fb.as_mut_ptr();
    assert_eq!(init(null_mut(), 0, 4, 0, p, rows, W, H), MlabStatus::NullPointer);
    assert_eq!(init(f, 0, 4, 0, null_mut(), rows, W, H), MlabStatus::NullPointer);
    let off = p.cast::<u8>().wrapping_add(4).cast::<MlabRow>();
    assert_eq!(init(f, 0, 4, 0, off, rows, W, H), MlabStatus::Misaligned);
    assert_eq!(init(f, 0, 4, 0, p, rows - 1, W, H), MlabStatus::StorageLength, "short");
    assert_eq!(init(f, 0, 4, 0, p, rows + 1, W, H), MlabStatus::StorageLength, "long");
    assert_eq!(init(f, 0, 4, 0, p, 0, W, H), MlabStatus::StorageLength, "size 0");
    assert_eq!(init(f, 0, 4, 0, p, 0, 0, H), MlabStatus::ZeroSize, "width 0");
    assert_eq!(init(f, 0, 4, 0, p, 0, W, 0), MlabStatus::ZeroSize, "height 0");
    assert_eq!(init(f, 0, 0, 0, p, rows, W, H), MlabStatus::UnsupportedLayers);
    assert_eq!(init(f, 0, 9, 0, p, rows, W, H), MlabStatus::UnsupportedLayers);
    assert_eq!(init(f, 7, 4, 0, p, rows, W, H), MlabStatus::InvalidArgument, "method");
    assert_eq!(
        init(f, 0, 4, 2, p, rows, W, H),
        MlabStatus::InvalidArgument,
        "arithmetic"
    );
    assert!(storage.iter().all(|r| r.bytes == [7; 8]), "storage untouched on error");
    assert_eq!(init(f, 0, 4, 1, p, rows, W, H), MlabStatus::Ok);
    assert!(storage[..rows].iter().all(|r| r.bytes != [7; 8]), "init clears");
}

/// The status of every kind of invalid fragment, per-pixel and in spans, is the kernel's
/// error for it, and the documented code.
#[test]
fn invalid_fragments_are_reported_not_dropped() {
    let nan = f32::NAN;
    let inf = f32::INFINITY;
    // (straight r, g, b, a, depth, status)
    let cases = [
        ([nan, 0.5, 0.5, 0.5], 1.0, MlabStatus::NanColor),
        ([0.5, inf, 0.5, 0.5], 1.0, MlabStatus::InfiniteColor),
        ([0.5, 0.5, -0.1, 0.5], 1.0, MlabStatus::NegativeColor),
        ([3.0, 0.5, 0.5, 0.5], 1.0, MlabStatus::ColorAboveOne),
        ([0.5, 0.5, 0.5, nan], 1.0, MlabStatus::NanAlpha),
        ([0.5, 0.5, 0.5, 1.5], 1.0, MlabStatus::AlphaOutOfRange),
        ([0.5, 0.5, 0.5, -0.5], 1.0, MlabStatus::AlphaOutOfRange),
        ([0.5, 0.5, 0.5, 0.5], nan, MlabStatus::NanDepth),
        ([0.5, 0.5, 0.5, 0.5], -inf, MlabStatus::InfiniteDepth),
    ];
    for (method, layers) in [(MLAB_METHOD_MLAB, 3), (MLAB_METHOD_HYBRID, 2)] {
        let mut c = c_fb(method, layers);
        let before = c.bytes();
        for (rgba, depth, want) in cases {
            let rust = Fragment::straight_rgba(rgba, depth).unwrap_err();
            assert_eq!(MlabStatus::from(rust), want, "{rgba:?} {depth}: the kernel's error");
            let [r, g, b, a] = rgba;
            let mut refused = 0u8;
            let mut span = SPAN;
            (span.r[5], span.g[5], span.b[5], span.a[5], span.depth[5]) = (r, g, b, a, depth);
            let mut keyed = SPAN_KEYED;
            (keyed.r[2], keyed.g[2], keyed.b[2], keyed.a[2], keyed.depth[2]) = (r, g, b, a, depth);
            // SAFETY: an initialized framebuffer; valid span and byte.
            unsafe {
                assert_eq!(mlab_insert_straight(&mut c.fb, 1, 1, r, g, b, a, depth), want);
                // The pixel is checked before the fragment.
                let outside = MlabStatus::OutOfBounds;
                assert_eq!(mlab_insert_straight(&mut c.fb, W, H, r, g, b, a, depth), outside);
                assert_eq!(c.bytes(), before, "nothing inserted");
                // In a span: the lane is refused, the others inserted.
                let st = mlab_insert_span_straight(&mut c.fb, 0, 0, &span, 0b0010_0001, &mut refused);
                assert_eq!((st, refused), (want, 0b0010_0000), "{rgba:?} {depth}");
                assert_ne!(c.bytes(), before, "lane 0 inserted");
                mlab_framebuffer_clear(&mut c.fb);
                // The keyed inserts: the same statuses.
                assert_eq!(mlab_insert_straight_keyed(&mut c.fb, 1, 1, r, g, b, a, depth, 9), want);
                assert_eq!(
                    mlab_insert_straight_keyed(&mut c.fb, W, H, r, g, b, a, depth, 9),
                    outside
                );
                assert_eq!(c.bytes(), before, "nothing inserted");
                let st = mlab_insert_span_straight_keyed(&mut c.fb, 0, 0, &keyed, 0b0000_0110, &mut refused);
                assert_eq!((st, refused), (want, 0b0000_0100), "keyed {rgba:?} {depth}");
                assert_ne!(c.bytes(), before, "lane 1 inserted");
                mlab_framebuffer_clear(&mut c.fb);
            }
        }
        // Premultiplied: a color above 1 is refused, above alpha is additive light.
        // SAFETY: as above.
        unsafe {
            assert_eq!(
                mlab_insert_premultiplied(&mut c.fb, 0, 0, 1.5, 0.0, 0.0, 1.0, 1.0),
                MlabStatus::ColorAboveOne
            );
            assert_eq!(
                mlab_insert_premultiplied(&mut c.fb, 0, 0, 0.9, 0.0, 0.0, 0.1, 1.0),
                MlabStatus::Ok
            );
            assert_eq!(
                mlab_insert_premultiplied_keyed(&mut c.fb, 0, 0, 1.5, 0.0, 0.0, 1.0, 1.0, 1),
                MlabStatus::ColorAboveOne
            );
            assert_eq!(
                mlab_insert_premultiplied_keyed(&mut c.fb, 0, 0, 0.9, 0.0, 0.0, 0.1, 1.0, 1),
                MlabStatus::Ok
            );
            let mut span = SPAN_KEYED;
            span.r[3] = 1.5;
            let mut refused = 0;
            let st = mlab_insert_span_premultiplied_keyed(&mut c.fb, 0, 0, &span, 0xff, &mut refused);
            assert_eq!((st, refused), (MlabStatus::ColorAboveOne, 0b1000));
        }
    }
}

#[test]
fn pixels_outside_are_reported() {
    let mut c = c_fb(MLAB_METHOD_MLAB, 2);
    let before = c.bytes();
    let mut refused = 0xaau8;
    // SAFETY: an initialized framebuffer, valid pointers.
    unsafe {
        for (x, y) in [(W, 0), (0, H), (u32::MAX, u32::MAX)] {
            assert_eq!(
                mlab_insert_straight(&mut c.fb, x, y, 0.5, 0.5, 0.5, 0.5, 1.0),
                MlabStatus::OutOfBounds
            );
            assert_eq!(
                mlab_insert_premultiplied(&mut c.fb, x, y, 0.5, 0.5, 0.5, 0.5, 1.0),
                MlabStatus::OutOfBounds
            );
            assert_eq!(
                mlab_insert_straight_keyed(&mut c.fb, x, y, 0.5, 0.5, 0.5, 0.5, 1.0, 1),
                MlabStatus::OutOfBounds
            );
            assert_eq!(
                mlab_insert_premultiplied_keyed(&mut c.fb, x, y, 0.5, 0.5, 0.5, 0.5, 1.0, 1),
                MlabStatus::OutOfBounds
            );
        }
        let st = mlab_insert_span_straight_keyed(&mut c.fb, 6, 0, &SPAN_KEYED, 0x80, &mut refused);
        assert_eq!((st, refused), (MlabStatus::OutOfBounds, 0xaa));
        let st = mlab_insert_span_premultiplied_keyed(&mut c.fb, 0, H, &SPAN_KEYED, 1, &mut refused);
        assert_eq!((st, refused), (MlabStatus::OutOfBounds, 0xaa));
        // Lane 7 of a span at x = 6 is pixel 13, outside a 13-pixel line; with lane 7 off it
        // fits.
        let st = mlab_insert_span_straight(&mut c.fb, 6, 0, &SPAN, 0x80, &mut refused);
        assert_eq!((st, refused), (MlabStatus::OutOfBounds, 0xaa));
        let st = mlab_insert_span_premultiplied(&mut c.fb, 0, H, &SPAN, 1, &mut refused);
        assert_eq!((st, refused), (MlabStatus::OutOfBounds, 0xaa));
        assert_eq!(c.bytes(), before);
        let st = mlab_insert_span_straight(&mut c.fb, 6, 0, &SPAN, 0x7f, &mut refused);
        assert_eq!((st, refused), (MlabStatus::Ok, 0));
        // The batch stops at the first fragment outside: the ones before are in.
        let frags = [(0, 0), (1, 2), (W, 1), (2, 2)].map(|(x, y)| MlabPixelFragment {
            x,
            y,
            rgba: [0.5; 4],
            depth: 1.0,
        });
        let mut inserted = 99;
        let st = mlab_insert_batch_straight(&mut c.fb, frags.as_ptr(), frags.len(), &mut inserted);
        assert_eq!((st, inserted), (MlabStatus::OutOfBounds, 2));
        let mut bad = frags;
        bad[1].rgba[3] = f32::NAN;
        let st = mlab_insert_batch_premultiplied(&mut c.fb, bad.as_ptr(), bad.len(), &mut inserted);
        assert_eq!((st, inserted), (MlabStatus::NanAlpha, 1));
        // Count 0: nothing to do.
        let st = mlab_insert_batch_straight(&mut c.fb, frags.as_ptr(), 0, &mut inserted);
        assert_eq!((st, inserted), (MlabStatus::Ok, 0));
        // The keyed batch: the same stops.
        let keyed = frags.map(|f| MlabPixelFragmentKeyed {
            x: f.x,
            y: f.y,
            rgba: f.rgba,
            depth: f.depth,
            key: f.x,
        });
        let st = mlab_insert_batch_straight_keyed(&mut c.fb, keyed.as_ptr(), keyed.len(), &mut inserted);
        assert_eq!((st, inserted), (MlabStatus::OutOfBounds, 2));
        let mut bad = keyed;
        bad[1].depth = f32::INFINITY;
        let st = mlab_insert_batch_premultiplied_keyed(&mut c.fb, bad.as_ptr(), bad.len(), &mut inserted);
        assert_eq!((st, inserted), (MlabStatus::InfiniteDepth, 1));
        inserted = 99;
        let st = mlab_insert_batch_premultiplied_keyed(&mut c.fb, null(), 0, &mut inserted);
        assert_eq!((st, inserted), (MlabStatus::Ok, 0), "count 0: null is an empty array");
    }
}

#[test]
fn span_and_batch_pointers_are_checked() {
    let mut c = c_fb(MLAB_METHOD_HYBRID, 4);
    let before = c.bytes();
    let mut refused = 0u8;
    let mut inserted = 0usize;
    let frag = MlabPixelFragment {
        x: 0,
        y: 0,
        rgba: [0.5; 4],
        depth: 1.0,
    };
    let mut buf = [0u32; 64];
    let off_span = buf.as_mut_ptr().cast::<u8>().wrapping_add(2).cast::<MlabFragmentSpan>();
    let off_frag = buf
        .as_mut_ptr()
        .cast::<u8>()
        .wrapping_add(2)
        .cast::<MlabPixelFragment>();
    // SAFETY: an initialized framebuffer; every pointer is null, misaligned (refused) or valid.
    unsafe {
        let fb = &mut c.fb as *mut MlabFramebuffer;
        assert_eq!(
            mlab_insert_span_straight(fb, 0, 0, null(), 1, &mut refused),
            MlabStatus::NullPointer
        );
        assert_eq!(
            mlab_insert_span_premultiplied(fb, 0, 0, &SPAN, 1, null_mut()),
            MlabStatus::NullPointer
        );
        assert_eq!(
            mlab_insert_span_straight(fb, 0, 0, off_span, 1, &mut refused),
            MlabStatus::Misaligned
        );
        assert_eq!(
            mlab_insert_batch_straight(fb, null(), 1, &mut inserted),
            MlabStatus::NullPointer
        );
        assert_eq!(
            mlab_insert_batch_premultiplied(fb, &frag, 1, null_mut()),
            MlabStatus::NullPointer
        );
        assert_eq!(
            mlab_insert_batch_straight(fb, off_frag, 1, &mut inserted),
            MlabStatus::Misaligned
        );
        assert_eq!(
            mlab_insert_batch_straight(fb, &frag, usize::MAX / 2, &mut inserted),
            MlabStatus::SizeOverflow
        );
    }
    assert_eq!(c.bytes(), before);
}

/// The keyed span and batch inserts check their pointers as the unkeyed ones: null
/// fragments, out-parameters, fragments off their 4-byte alignment, an overflowing count.
#[test]
fn keyed_span_and_batch_pointers_are_checked() {
    let mut c = c_fb(MLAB_METHOD_MLAB, 4);
    let before = c.bytes();
    let (mut refused, mut inserted) = (0xaau8, 77usize);
    let frag = MlabPixelFragmentKeyed {
        x: 0,
        y: 0,
        rgba: [0.5; 4],
        depth: 1.0,
        key: 5,
    };
    let mut buf = [0u32; 64];
    let base = buf.as_mut_ptr().cast::<u8>();
    let off_span = base.wrapping_add(2).cast::<MlabFragmentSpanKeyed>();
    let off_frag = base.wrapping_add(1).cast::<MlabPixelFragmentKeyed>();
    let off_inserted = base.wrapping_add(4).cast::<usize>();
    assert_eq!(align_of::<MlabFragmentSpanKeyed>(), 4);
    assert_eq!(align_of::<MlabPixelFragmentKeyed>(), 4);
    assert_eq!(size_of::<MlabPixelFragmentKeyed>(), 32);
    assert_eq!(size_of::<MlabFragmentSpanKeyed>(), 192);
    // SAFETY: an initialized framebuffer; every pointer is null, misaligned (refused) or valid.
    unsafe {
        let fb = &mut c.fb as *mut MlabFramebuffer;
        for (straight, name) in [(true, "straight"), (false, "premultiplied")] {
            let span = |f: *const MlabFragmentSpanKeyed, r: *mut u8| {
                if straight {
                    mlab_insert_span_straight_keyed(fb, 0, 0, f, 1, r)
                } else {
                    mlab_insert_span_premultiplied_keyed(fb, 0, 0, f, 1, r)
                }
            };
            let batch = |f: *const MlabPixelFragmentKeyed, n: usize, i: *mut usize| {
                if straight {
                    mlab_insert_batch_straight_keyed(fb, f, n, i)
                } else {
                    mlab_insert_batch_premultiplied_keyed(fb, f, n, i)
                }
            };
            assert_eq!(span(null(), &mut refused), MlabStatus::NullPointer, "{name}");
            assert_eq!(span(&SPAN_KEYED, null_mut()), MlabStatus::NullPointer, "{name}");
            assert_eq!(span(off_span, &mut refused), MlabStatus::Misaligned, "{name}");
            assert_eq!(batch(null(), 1, &mut inserted), MlabStatus::NullPointer, "{name}");
            assert_eq!(batch(&frag, 1, null_mut()), MlabStatus::NullPointer, "{name}");
            assert_eq!(batch(off_frag, 1, &mut inserted), MlabStatus::Misaligned, "{name}");
            assert_eq!(batch(&frag, 1, off_inserted), MlabStatus::Misaligned, "{name}");
            assert_eq!(
                batch(&frag, usize::MAX / 16, &mut inserted),
                MlabStatus::SizeOverflow,
                "{name}"
            );
        }
        // The framebuffer pointer itself: null and misaligned (`every_call_returns` covers
        // the rest).
        let off_fb = base.wrapping_add(4).cast::<MlabFramebuffer>();
        for f in [null_mut(), off_fb] {
            let want = if f.is_null() {
                MlabStatus::NullPointer
            } else {
                MlabStatus::Misaligned
            };
            assert_eq!(mlab_insert_straight_keyed(f, 0, 0, 0.5, 0.5, 0.5, 0.5, 1.0, 1), want);
            assert_eq!(
                mlab_insert_span_straight_keyed(f, 0, 0, &SPAN_KEYED, 1, &mut refused),
                want
            );
            assert_eq!(mlab_insert_batch_straight_keyed(f, &frag, 1, &mut inserted), want);
        }
    }
    assert_eq!((refused, inserted), (0xaa, 77), "out-parameters untouched");
    assert_eq!(c.bytes(), before, "nothing inserted");
}

/// The order of the checks, one rule for every insert: the pointers and the state, then the
/// coordinates (the pixel, or every lane that is on), then the fragment's values. An insert
/// of nothing (mask 0, count 0) reads no fragment and checks no coordinate.
#[test]
fn checks_come_in_one_order() {
    let mut c = c_fb(MLAB_METHOD_MLAB, 2);
    let before = c.bytes();
    let nan = f32::NAN;
    let mut span = SPAN;
    span.a[1] = nan;
    let mut keyed = SPAN_KEYED;
    keyed.depth[1] = nan;
    let bad = MlabPixelFragment {
        x: W,
        y: 0,
        rgba: [0.5, 0.5, 0.5, nan],
        depth: 1.0,
    };
    let bad_keyed = MlabPixelFragmentKeyed {
        x: 0,
        y: H,
        rgba: [nan; 4],
        depth: 1.0,
        key: 1,
    };
    let (mut refused, mut inserted) = (0xaau8, 99usize);
    let oob = MlabStatus::OutOfBounds;
    // SAFETY: an initialized framebuffer; every pointer valid (or null where nothing is read).
    unsafe {
        let fb = &mut c.fb as *mut MlabFramebuffer;
        // An invalid fragment at a pixel outside: the pixel's status.
        assert_eq!(mlab_insert_straight(fb, W, 0, nan, 0.5, 0.5, 0.5, 1.0), oob);
        assert_eq!(mlab_insert_premultiplied(fb, 0, H, 0.5, 0.5, 0.5, nan, 1.0), oob);
        assert_eq!(mlab_insert_straight_keyed(fb, 99, 0, 0.5, 0.5, 0.5, 0.5, nan, 4), oob);
        assert_eq!(
            mlab_insert_premultiplied_keyed(fb, 0, 99, -1.0, 0.5, 0.5, 0.5, 1.0, 4),
            oob
        );
        // A NaN lane and a lane outside (lane 7 at x = 6 is pixel 13): the lane outside's
        // status, nothing inserted, `*refused` unchanged.
        for mask in [0b1000_0010, 0b1000_0011] {
            assert_eq!(mlab_insert_span_straight(fb, 6, 0, &span, mask, &mut refused), oob);
            assert_eq!(mlab_insert_span_premultiplied(fb, 6, 0, &span, mask, &mut refused), oob);
            assert_eq!(
                mlab_insert_span_straight_keyed(fb, 6, 0, &keyed, mask, &mut refused),
                oob
            );
            assert_eq!(
                mlab_insert_span_premultiplied_keyed(fb, 6, 0, &keyed, mask, &mut refused),
                oob
            );
        }
        assert_eq!(refused, 0xaa);
        // In a batch, each fragment's pixel before its values.
        assert_eq!(mlab_insert_batch_straight(fb, &bad, 1, &mut inserted), oob);
        assert_eq!(mlab_insert_batch_premultiplied(fb, &bad, 1, &mut inserted), oob);
        assert_eq!(mlab_insert_batch_straight_keyed(fb, &bad_keyed, 1, &mut inserted), oob);
        assert_eq!(
            mlab_insert_batch_premultiplied_keyed(fb, &bad_keyed, 1, &mut inserted),
            oob
        );
        assert_eq!(inserted, 0);
        assert_eq!(c.bytes(), before, "nothing inserted");

        // Mask 0 inserts nothing, wherever it is: x and y alike, fragments not read.
        for (x, y) in [(1000, 0), (0, 1000), (u32::MAX, u32::MAX), (0, 0)] {
            for (f, k) in [(&SPAN as *const _, &SPAN_KEYED as *const _), (null(), null())] {
                refused = 0xaa;
                assert_eq!(mlab_insert_span_straight(fb, x, y, f, 0, &mut refused), MlabStatus::Ok);
                assert_eq!(refused, 0, "({x}, {y})");
                refused = 0xaa;
                assert_eq!(
                    mlab_insert_span_premultiplied(fb, x, y, f, 0, &mut refused),
                    MlabStatus::Ok
                );
                assert_eq!(
                    mlab_insert_span_straight_keyed(fb, x, y, k, 0, &mut refused),
                    MlabStatus::Ok
                );
                assert_eq!(
                    mlab_insert_span_premultiplied_keyed(fb, x, y, k, 0, &mut refused),
                    MlabStatus::Ok
                );
                assert_eq!(refused, 0, "({x}, {y})");
            }
        }
        // Its out-parameter is still written, so still checked.
        assert_eq!(
            mlab_insert_span_straight(fb, 0, 0, &SPAN, 0, null_mut()),
            MlabStatus::NullPointer
        );
        // Count 0 inserts nothing: a null pointer (an empty std::vector's data()) is fine, as
        // is any other, which is not read.
        let off = [0u32; 16].as_ptr().cast::<u8>().wrapping_add(1);
        for f in [null(), off.cast(), &bad as *const MlabPixelFragment] {
            inserted = 99;
            assert_eq!(mlab_insert_batch_straight(fb, f, 0, &mut inserted), MlabStatus::Ok);
            assert_eq!(inserted, 0);
            inserted = 99;
            assert_eq!(mlab_insert_batch_premultiplied(fb, f, 0, &mut inserted), MlabStatus::Ok);
            assert_eq!(inserted, 0);
        }
        for f in [null(), off.cast(), &bad_keyed as *const MlabPixelFragmentKeyed] {
            inserted = 99;
            assert_eq!(
                mlab_insert_batch_straight_keyed(fb, f, 0, &mut inserted),
                MlabStatus::Ok
            );
            assert_eq!(inserted, 0);
            inserted = 99;
            assert_eq!(
                mlab_insert_batch_premultiplied_keyed(fb, f, 0, &mut inserted),
                MlabStatus::Ok
            );
            assert_eq!(inserted, 0);
        }
        assert_eq!(
            mlab_insert_batch_straight(fb, null(), 0, null_mut()),
            MlabStatus::NullPointer
        );
    }
    assert_eq!(c.bytes(), before, "nothing inserted");
}

/// The field of a framebuffer struct at byte `offset`, as a C caller reaches the fields the
/// header shows (`fb.height`): the layout is `#[repr(C)]` (pointer, size_t, then four u32).
fn field<T>(fb: &mut MlabFramebuffer, offset: usize) -> &mut T {
    // SAFETY: `offset` is that of a field of type `T` in the 64-bit layout (checked by the
    // caller against the values init wrote).
    unsafe { &mut *(fb as *mut MlabFramebuffer).cast::<u8>().add(offset).cast::<T>() }
}

/// A struct changed since its init or band is refused: `MLAB_STATUS_NOT_INITIALIZED`, by
/// every call, before its rows are touched.
#[cfg(target_pointer_width = "64")]
#[test]
fn a_changed_struct_is_refused() {
    const STORAGE_ROWS: usize = 8;
    const HEIGHT: usize = 20;
    for (method, layers) in [(MLAB_METHOD_MLAB, 2), (MLAB_METHOD_HYBRID, 3)] {
        let mut c = c_fb(method, layers);
        let before = c.bytes();
        // The offsets are those of the fields: the values init wrote.
        assert_eq!(*field::<usize>(&mut c.fb, STORAGE_ROWS), c.storage.len());
        assert_eq!(*field::<u32>(&mut c.fb, 16), W);
        assert_eq!(*field::<u32>(&mut c.fb, HEIGHT), H);
        // `m = fb; m.height += 3; mlab_rows_needed(..., H + 3, &m.storage_rows);
        // mlab_insert_straight(&m, 0, H + 2, ...)`: would write past the storage.
        let mut m = c.fb;
        *field::<u32>(&mut m, HEIGHT) += 3;
        // SAFETY: a size_t to write.
        let st = unsafe { mlab_rows_needed(method, layers, W, H + 3, field::<usize>(&mut m, STORAGE_ROWS)) };
        assert_eq!(st, MlabStatus::Ok);
        // SAFETY: `m` is refused before its (too short) storage is touched.
        let st = unsafe { mlab_insert_straight(&mut m, 0, H + 2, 0.5, 0.5, 0.5, 0.5, 1.0) };
        assert_eq!(st, MlabStatus::NotInitialized);
        every_call_returns(&mut m, MlabStatus::NotInitialized, "height and storage_rows changed");
        // Each field alone: the pointer, the length, width, height, first pixel, kind.
        for (offset, size, what) in [
            (0, 8, "storage"),
            (STORAGE_ROWS, 8, "storage_rows"),
            (16, 4, "width"),
            (HEIGHT, 4, "height"),
            (24, 4, "first"),
            (28, 4, "tag"),
        ] {
            for bit in [0, 3, 5, 31] {
                let mut m = c.fb;
                let b = field::<u8>(&mut m, offset + bit / 8 % size);
                *b ^= 1 << (bit % 8);
                every_call_returns(&mut m, MlabStatus::NotInitialized, &format!("{what} bit {bit}"));
            }
        }
        assert_eq!(c.bytes(), before, "nothing written");
        // A copy, anywhere in memory, is the same view: accepted.
        let mut copy = Box::new(c.fb);
        every_call_returns_ok(&mut *copy);
    }
}

#[test]
fn resolves_refuse_bad_outputs() {
    let c = c_fb(MLAB_METHOD_MLAB, 1);
    let n = (W * H) as usize;
    let mut out8 = vec![[9u8; 4]; n + 1];
    let mut out32 = vec![mlab::glam::Vec4::splat(9.0); n + 1];
    let mut out16 = vec![[9u16; 4]; n + 1];
    let p8 = out8.as_mut_ptr().cast::<u8>();
    let p32 = out32.as_mut_ptr().cast::<f32>();
    let p16 = out16.as_mut_ptr().cast::<u16>();
    let fb = &c.fb as *const MlabFramebuffer;
    let bad_bg = MlabBackground { kind: 2, rgb: [0.0; 3] };
    // SAFETY: outputs valid for n + 1 pixels (or null / misaligned: refused).
    unsafe {
        for len in [0, n - 1, n + 1] {
            assert_eq!(
                mlab_resolve_rgba8(fb, OPAQUE, p8, len),
                MlabStatus::OutputLength,
                "{len}"
            );
            assert_eq!(
                mlab_resolve_f32(fb, OPAQUE, p32, len),
                MlabStatus::OutputLength,
                "{len}"
            );
            assert_eq!(
                mlab_resolve_rgba16f(fb, OPAQUE, p16, len),
                MlabStatus::OutputLength,
                "{len}"
            );
        }
        assert_eq!(mlab_resolve_rgba8(fb, OPAQUE, null_mut(), n), MlabStatus::NullPointer);
        assert_eq!(mlab_resolve_f32(fb, OPAQUE, null_mut(), n), MlabStatus::NullPointer);
        assert_eq!(mlab_resolve_rgba16f(fb, OPAQUE, null_mut(), n), MlabStatus::NullPointer);
        // f32 output: 16-byte alignment; RGBA16F: 2.
        assert_eq!(
            mlab_resolve_f32(fb, OPAQUE, p32.wrapping_add(1), n),
            MlabStatus::Misaligned
        );
        let p16_odd = p16.cast::<u8>().wrapping_add(1).cast::<u16>();
        assert_eq!(mlab_resolve_rgba16f(fb, OPAQUE, p16_odd, n), MlabStatus::Misaligned);
        assert_eq!(mlab_resolve_rgba8(fb, bad_bg, p8, n), MlabStatus::InvalidArgument);
        assert_eq!(mlab_resolve_f32(fb, bad_bg, p32, n), MlabStatus::InvalidArgument);
        assert_eq!(mlab_resolve_rgba16f(fb, bad_bg, p16, n), MlabStatus::InvalidArgument);
    }
    assert!(out8.iter().all(|p| *p == [9; 4]), "untouched");
    assert!(out32.iter().all(|p| *p == mlab::glam::Vec4::splat(9.0)), "untouched");
    assert!(out16.iter().all(|p| *p == [9; 4]), "untouched");
    // SAFETY: as above, the right length: written.
    unsafe {
        assert_eq!(mlab_resolve_rgba8(fb, OPAQUE, p8, n), MlabStatus::Ok);
        assert_eq!(out8[0], [255; 4], "empty pixel over white");
        assert_eq!(out8[n], [9; 4], "nothing past the end");
    }
}

#[test]
fn bands_refuse_bad_lines() {
    let c = c_fb(MLAB_METHOD_MLAB, 2);
    let mut band = MaybeUninit::uninit();
    // SAFETY: an initialized framebuffer; `band` writable (or null: refused).
    unsafe {
        assert_eq!(
            mlab_framebuffer_band(&c.fb, 0, 0, band.as_mut_ptr()),
            MlabStatus::ZeroSize
        );
        assert_eq!(
            mlab_framebuffer_band(&c.fb, 1, H, band.as_mut_ptr()),
            MlabStatus::OutOfBounds
        );
        assert_eq!(
            mlab_framebuffer_band(&c.fb, u32::MAX, 2, band.as_mut_ptr()),
            MlabStatus::OutOfBounds
        );
        every_call_returns(band.as_mut_ptr(), MlabStatus::NotInitialized, "failed band");
        assert_eq!(mlab_framebuffer_band(&c.fb, 0, 1, null_mut()), MlabStatus::NullPointer);
        assert_eq!(
            mlab_framebuffer_band(&c.fb, 1, H - 1, band.as_mut_ptr()),
            MlabStatus::Ok
        );
        every_call_returns_ok(band.as_mut_ptr());
    }
}

#[test]
fn every_status_has_its_message() {
    let text = |code: i32| {
        // SAFETY: mlab_error_message returns a static NUL-terminated string.
        unsafe { std::ffi::CStr::from_ptr(mlab_error_message(code)) }
            .to_str()
            .unwrap()
            .to_owned()
    };
    let all = (0..=MlabStatus::Internal as i32).map(text).collect::<Vec<_>>();
    let mut unique = all.clone();
    unique.sort();
    unique.dedup();
    assert_eq!(unique.len(), all.len(), "one message per code: {all:?}");
    assert_eq!(all[0], "ok");
    for code in [-1, MlabStatus::Internal as i32 + 1, 1000, i32::MIN] {
        assert_eq!(text(code), "unknown mlab status code");
    }
    // The fragment errors read as the kernel's.
    for e in [
        FragmentError::NanColor,
        FragmentError::InfiniteColor,
        FragmentError::NegativeColor,
        FragmentError::ColorAboveOne,
        FragmentError::NanAlpha,
        FragmentError::AlphaOutOfRange,
        FragmentError::NanDepth,
        FragmentError::InfiniteDepth,
    ] {
        assert_eq!(text(MlabStatus::from(e) as i32), e.to_string());
    }
    assert_eq!(mlab_abi_version(), MLAB_ABI_VERSION);
}
