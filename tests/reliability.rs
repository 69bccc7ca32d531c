//! The bad-input policy of `docs/reliability.md`, one test per row of its table (the test
//! names are the row names), plus the reproducers of open kernel findings (`#[ignore]`d
//! until the kernel owner fixes them; run them with `cargo test --test reliability -- --ignored`).

use mlab::Framebuffer;
use mlab::TailFormat as _;
use mlab::glam::{Vec3, Vec4};
use mlab::half::f16;
const INV255: f32 = 1.0 / 255.0;
use mlab::{
    Background, BlendingArray, Fragment, FragmentError as E, FramebufferError as FbE, Hybrid, HybridFramebuffer,
    MlabFramebuffer, Paper, Resolved, Row, hybrid, hybrid::PaperTail as Tail, mlab as mlab_kernel, resolve_rows,
    to_rgba8, to_rgba16f,
};

const OK: Vec3 = Vec3::splat(0.25);

/// Every public constructor on the same premultiplied color, alpha and depth
/// (`with_transmittance` gets `1 - alpha`, `additive` ignores alpha).
fn all_ctors(c: Vec3, a: f32, z: f32) -> [Result<Fragment, E>; 4] {
    [
        Fragment::premultiplied(c, a, z),
        Fragment::straight(c, a, z),
        Fragment::with_transmittance(c, 1.0 - a, z),
        Fragment::premultiplied_rgba(c.extend(a).to_array(), z),
    ]
}

fn assert_finite_in_range(r: Resolved, max_color: f32) {
    assert!((0.0..=1.0).contains(&r.transmittance), "{r:?}");
    let max_color = max_color * (1.0 + 4.0 * f32::EPSILON);
    assert!(
        r.color.to_array().iter().all(|c| (0.0..=max_color).contains(c)),
        "{r:?}"
    );
}

// ---- Fragments -------------------------------------------------------------------------

#[test]
fn nan_depth() {
    for z in [
        f32::NAN,
        -f32::NAN,
        f32::from_bits(0x7fc0_1234),
        f32::from_bits(0xff80_0001),
    ] {
        for r in all_ctors(OK, 0.5, z) {
            assert_eq!(r, Err(E::NanDepth));
        }
        assert_eq!(Fragment::additive(OK, z), Err(E::NanDepth));
    }
}

#[test]
fn infinite_depth() {
    for z in [f32::INFINITY, f32::NEG_INFINITY] {
        for r in all_ctors(OK, 0.5, z) {
            assert_eq!(r, Err(E::InfiniteDepth));
        }
        assert_eq!(Fragment::additive(OK, z), Err(E::InfiniteDepth));
    }
    // Every finite depth is accepted, down to the extremes and subnormals; -0.0 is kept.
    for z in [f32::MAX, -f32::MAX, f32::from_bits(1), -0.0] {
        let f = Fragment::premultiplied(OK, 0.5, z).unwrap();
        assert_eq!(
            <mlab::Paper as mlab::Arithmetic>::quantize(&f, 0).depth().to_bits(),
            z.to_bits()
        );
    }
}

#[test]
fn nan_alpha() {
    for a in [f32::NAN, -f32::NAN] {
        assert_eq!(Fragment::premultiplied(OK, a, 1.0), Err(E::NanAlpha));
        assert_eq!(Fragment::straight(OK, a, 1.0), Err(E::NanAlpha));
        assert_eq!(Fragment::with_transmittance(OK, a, 1.0), Err(E::NanAlpha));
        assert_eq!(
            Fragment::premultiplied_rgba(OK.extend(a).to_array(), 1.0),
            Err(E::NanAlpha)
        );
    }
}

#[test]
fn alpha_out_of_range() {
    for a in [
        -1e-30,
        -0.01,
        1.000_000_1,
        2.0,
        f32::INFINITY,
        f32::NEG_INFINITY,
        f32::MAX,
    ] {
        assert_eq!(
            Fragment::premultiplied(OK, a, 1.0),
            Err(E::AlphaOutOfRange),
            "alpha {a}"
        );
        assert_eq!(Fragment::straight(OK, a, 1.0), Err(E::AlphaOutOfRange), "alpha {a}");
        assert_eq!(
            Fragment::with_transmittance(OK, a, 1.0),
            Err(E::AlphaOutOfRange),
            "T {a}"
        );
        assert_eq!(
            Fragment::premultiplied_rgba(OK.extend(a).to_array(), 1.0),
            Err(E::AlphaOutOfRange)
        );
    }
    // The closed interval is accepted, -0.0 included (it quantizes to 0).
    for a in [0.0, -0.0, 1.0, f32::from_bits(1)] {
        let f = Fragment::premultiplied(Vec3::ZERO, a, 1.0).unwrap();
        assert_eq!(
            <mlab::Paper as mlab::Arithmetic>::quantize(&f, 0).transmittance(),
            255 - (a * 255.0 + 0.5) as u8
        );
    }
}

#[test]
fn nan_color() {
    for c in [Vec3::new(f32::NAN, 0.0, 0.0), Vec3::new(0.0, 0.0, -f32::NAN)] {
        for r in all_ctors(c, 0.5, 1.0) {
            assert_eq!(r, Err(E::NanColor));
        }
        assert_eq!(Fragment::additive(c, 1.0), Err(E::NanColor));
    }
}

#[test]
fn infinite_color() {
    for c in [
        Vec3::new(0.0, f32::INFINITY, 0.0),
        Vec3::new(0.0, 0.0, f32::NEG_INFINITY),
    ] {
        for r in all_ctors(c, 0.5, 1.0) {
            assert_eq!(r, Err(E::InfiniteColor));
        }
        assert_eq!(Fragment::additive(c, 1.0), Err(E::InfiniteColor));
    }
}

#[test]
fn negative_color() {
    for c in [
        Vec3::new(-0.01, 0.0, 0.0),
        Vec3::new(0.0, 0.0, -f32::from_bits(1)),
        Vec3::splat(-f32::MAX),
    ] {
        for r in all_ctors(c, 0.5, 1.0) {
            assert_eq!(r, Err(E::NegativeColor));
        }
        assert_eq!(Fragment::additive(c, 1.0), Err(E::NegativeColor));
    }
    // -0.0 is zero: accepted, quantized to byte 0.
    let f = Fragment::premultiplied(Vec3::new(-0.0, 0.0, -0.0), 0.5, 1.0).unwrap();
    assert_eq!(<mlab::Paper as mlab::Arithmetic>::quantize(&f, 0).color(), [0, 0, 0]);
}

#[test]
fn premultiplied_color_above_one() {
    assert_eq!(
        Fragment::premultiplied(Vec3::new(1.000_000_1, 0.0, 0.0), 1.0, 1.0),
        Err(E::ColorAboveOne)
    );
    assert_eq!(
        Fragment::premultiplied_rgba([0.0, 2.0, 0.0, 1.0], 1.0),
        Err(E::ColorAboveOne)
    );
    assert_eq!(
        Fragment::with_transmittance(Vec3::splat(1.5), 0.0, 1.0),
        Err(E::ColorAboveOne)
    );
    assert_eq!(Fragment::additive(Vec3::new(0.0, 0.0, 1.5), 1.0), Err(E::ColorAboveOne));
    // Straight color is checked after the multiply by alpha: 3 * 0.5 is refused, 3 * 0.25 is not.
    assert_eq!(
        Fragment::straight(Vec3::new(3.0, 0.0, 0.0), 0.5, 1.0),
        Err(E::ColorAboveOne)
    );
    let f = Fragment::straight(Vec3::new(3.0, 0.0, 0.0), 0.25, 1.0).unwrap();
    assert_eq!(f.color(), Vec3::new(0.75, 0.0, 0.0));
    // Huge finite straight color with alpha 0 is zero light, accepted.
    assert_eq!(
        <mlab::Paper as mlab::Arithmetic>::quantize(&Fragment::straight(Vec3::splat(f32::MAX), 0.0, 1.0).unwrap(), 0),
        Row::new([0; 3], 255, 1.0)
    );
}

#[test]
fn premultiplied_color_above_alpha_is_additive_light() {
    // Valid: color 0.5 with alpha 0.1 (partly additive) and alpha 0 (pure light).
    let part = Fragment::premultiplied(Vec3::new(0.5, 0.0, 0.0), 0.1, 2.0).unwrap();
    let light = Fragment::additive(Vec3::new(0.0, 0.4, 0.0), 1.0).unwrap();
    assert_eq!(
        <mlab::Paper as mlab::Arithmetic>::quantize(&light, 0),
        Row::new([0, 102, 0], 255, 1.0)
    );
    let mut b = BlendingArray::<4, Paper>::new();
    b.insert(&part);
    b.insert(&light);
    let r = b.resolve();
    // The light occludes nothing: the background is seen through both at 1 - 0.1.
    assert!((r.transmittance - 229.0 / 255.0).abs() < 1e-6, "{r:?}");
    assert!(
        (r.color - Vec3::new(128.0 / 255.0, 102.0 / 255.0, 0.0))
            .abs()
            .max_element()
            < 1e-6,
        "{r:?}"
    );
    // HT keeps the light when it leaves the head (the paper's T != 1 test would drop it).
    let mut h = Hybrid::<0, Paper>::new();
    h.insert(&light);
    assert_eq!(h.tail().color_sum(), [0, 102, 0]);
}

#[test]
fn several_defects_at_once() {
    // NaN comes first, in the documented order depth, alpha, color.
    let nan = f32::NAN;
    assert_eq!(Fragment::premultiplied(Vec3::splat(nan), nan, nan), Err(E::NanDepth));
    assert_eq!(
        Fragment::premultiplied(Vec3::splat(nan), nan, f32::INFINITY),
        Err(E::NanAlpha)
    );
    assert_eq!(
        Fragment::premultiplied(Vec3::splat(nan), 7.0, f32::INFINITY),
        Err(E::NanColor)
    );
    // Then infinities (color, then depth), then ranges (negative color, alpha, color above one).
    let inf = f32::INFINITY;
    assert_eq!(
        Fragment::premultiplied(Vec3::new(inf, -1.0, 0.0), 7.0, inf),
        Err(E::InfiniteColor)
    );
    assert_eq!(
        Fragment::premultiplied(Vec3::new(2.0, -1.0, 0.0), 7.0, inf),
        Err(E::InfiniteDepth)
    );
    assert_eq!(
        Fragment::premultiplied(Vec3::new(-1.0, 0.0, 0.0), 0.5, inf),
        Err(E::InfiniteDepth)
    );
    assert_eq!(
        Fragment::premultiplied(Vec3::new(2.0, -1.0, 0.0), inf, 1.0),
        Err(E::NegativeColor)
    );
    assert_eq!(
        Fragment::premultiplied(Vec3::splat(2.0), 7.0, 1.0),
        Err(E::AlphaOutOfRange)
    );
    assert_eq!(Fragment::straight(Vec3::splat(4.0), 0.5, 1.0), Err(E::ColorAboveOne));
    // `with_transmittance` checks its transmittance argument before anything else.
    assert_eq!(Fragment::with_transmittance(OK, 2.0, nan), Err(E::AlphaOutOfRange));
}

// ---- Framebuffers ----------------------------------------------------------------------

#[test]
fn coordinates_outside_the_buffer() {
    let f = Fragment::straight(Vec3::X, 0.5, 1.0).unwrap();
    let mut storage = vec![Row::EMPTY; 3 * 2 * 2];
    let mut fb = MlabFramebuffer::<2>::new(&mut storage, 3, 2).unwrap();
    for (x, y) in [(3, 0), (0, 2), (u32::MAX, u32::MAX), (3, 1)] {
        let e = FbE::OutOfBounds {
            x,
            y,
            width: 3,
            height: 2,
        };
        assert_eq!(fb.insert(x, y, &f), Err(e));
        assert_eq!(
            fb.insert_row(x, y, <mlab::Paper as mlab::Arithmetic>::quantize(&f, 0)),
            Err(e)
        );
        assert_eq!(fb.pixel(x, y), Err(e));
        assert_eq!(fb.resolve(x, y), Err(e));
    }
    assert!(
        storage.iter().all(|r| r.is_empty()),
        "a refused insert changed the storage"
    );

    let mut storage = vec![Row::EMPTY; 3 * 2 * 3];
    let mut fb = HybridFramebuffer::<2>::new(&mut storage, 3, 2).unwrap();
    let e = FbE::OutOfBounds {
        x: 0,
        y: 2,
        width: 3,
        height: 2,
    };
    assert_eq!(fb.insert(0, 2, &f), Err(e));
    assert_eq!(fb.pixel(0, 2), Err(e));
    assert_eq!(fb.resolve(0, 2), Err(e));
    assert!(storage.iter().all(|r| r.is_empty()));
}

#[test]
fn storage_of_the_wrong_length() {
    let mut storage = vec![Row::EMPTY; 7];
    assert_eq!(
        MlabFramebuffer::<2>::new(&mut storage, 2, 2).err(),
        Some(FbE::StorageLength { expected: 8, actual: 7 })
    );
    assert_eq!(
        HybridFramebuffer::<1>::new(&mut storage, 2, 2).err(),
        Some(FbE::StorageLength { expected: 8, actual: 7 })
    );
    assert_eq!(
        MlabFramebuffer::<1>::new(&mut storage, 0, 5).err(),
        Some(FbE::StorageLength { expected: 0, actual: 7 })
    );
    // width * height * rows per pixel beyond usize.
    assert_eq!(
        MlabFramebuffer::<2>::new(&mut [], u32::MAX, u32::MAX).err(),
        Some(FbE::SizeOverflow)
    );
    assert_eq!(
        HybridFramebuffer::<3>::new(&mut [], u32::MAX, u32::MAX).err(),
        Some(FbE::SizeOverflow)
    );
    assert_eq!(
        MlabFramebuffer::<2>::rows_needed(u32::MAX, u32::MAX),
        Err(FbE::SizeOverflow)
    );
    // A 0 x 0 framebuffer over empty storage is valid and resolves into an empty output.
    let fb = MlabFramebuffer::<4>::new(&mut [], 0, 0).unwrap();
    assert_eq!(fb.resolve_rgba8(&mut [], Background::Transparent), Ok(()));
    assert!(storage.iter().all(|r| r.is_empty()));
}

#[test]
fn output_of_the_wrong_length() {
    let mut storage = vec![Row::EMPTY; 2 * 2 * 2];
    let fb = MlabFramebuffer::<2>::new(&mut storage, 2, 2).unwrap();
    let bg = Background::Opaque(Vec3::ONE);
    let mut small = [[9u8; 4]; 3];
    assert_eq!(
        fb.resolve_rgba8(&mut small, bg),
        Err(FbE::OutputLength { expected: 4, actual: 3 })
    );
    assert_eq!(small, [[9; 4]; 3], "a refused resolve wrote its output");
    let mut big = [Vec4::splat(9.0); 5];
    assert_eq!(
        fb.resolve_into(&mut big, bg),
        Err(FbE::OutputLength { expected: 4, actual: 5 })
    );
    assert_eq!(big, [Vec4::splat(9.0); 5]);
    let mut storage = vec![Row::EMPTY; 2 * 2 * 2];
    let fb = HybridFramebuffer::<1>::new(&mut storage, 2, 2).unwrap();
    let mut halves = [[f16::ONE; 4]; 0];
    assert_eq!(
        fb.resolve_rgba16f(&mut halves, bg),
        Err(FbE::OutputLength { expected: 4, actual: 0 })
    );
}

// ---- Rows and tails read back from bytes ----------------------------------------------

#[test]
fn garbage_rows_read_back_from_bytes() {
    let nan = f32::NAN;
    // Any 8 bytes are a row. The zeroed row is opaque black at depth 0, not empty.
    let zero = Row::from_bytes([0; 8]);
    assert!(!zero.is_empty() && !zero.is_invisible());
    assert_eq!(
        resolve_rows(&[zero]),
        Resolved {
            color: Vec3::ZERO,
            transmittance: 0.0
        }
    );

    // Resolve takes rows in the given order, sorted or not, NaN depths included: finite,
    // color in [0, rows], transmittance in [0, 1].
    let rows = [
        Row::from_bytes([255; 8]),
        Row::new([255, 0, 255], 255, nan),
        Row::new([255; 3], 255, 1.0),
    ];
    let r = resolve_rows(&rows);
    assert_finite_in_range(r, rows.len() as f32);
    assert_eq!(r.color.x, 1.0 + 1.0 + 1.0);

    // A new row with a NaN depth never compares nearer: it is merged behind the last row.
    let front = Row::new([10, 0, 0], 200, 1.0);
    let nan_row = Row::new([20, 0, 0], 100, nan);
    let mut full = [front, Row::new([0, 30, 0], 128, 2.0)];
    mlab_kernel::insert_with::<mlab::Unbiased, _>(&mut full, nan_row);
    assert_eq!(
        full,
        [
            front,
            <mlab::Unbiased as mlab::Arithmetic>::merge(
                Row::new([0, 30, 0], 128, 2.0),
                nan_row,
                mlab::mlab::row_hash(nan_row, 0)
            )
        ]
    );
    // ... and when the array is not full, it is merged behind the empty row: its colors and
    // T as they were; the depth is the empty row's (+infinity) in the paper's arithmetic,
    // and in the unbiased one the opacity-weighted key between +infinity's and the NaN's,
    // which is a NaN pattern (garbage stays garbage; deterministic, no panic).
    let mut open = [front, Row::EMPTY];
    mlab_kernel::insert_with::<mlab::Paper, _>(&mut open, nan_row);
    assert_eq!(open, [front, Row::new([20, 0, 0], 100, f32::INFINITY)]);
    let mut open = [front, Row::EMPTY];
    mlab_kernel::insert_with::<mlab::Unbiased, _>(&mut open, nan_row);
    assert_eq!(
        (open[0], open[1].color(), open[1].transmittance()),
        (front, [20, 0, 0], 100)
    );
    assert!(open[1].depth().is_nan());
    // Rows already holding a NaN depth are passed over by new rows (never swapped).
    let mut with_nan = [nan_row, Row::EMPTY];
    mlab_kernel::insert_with::<mlab::Unbiased, _>(&mut with_nan, front);
    assert_eq!(with_nan.map(|r| r.to_bytes()), [nan_row.to_bytes(), front.to_bytes()]);
    // Unsorted rows: the same steps of Listing 1, no panic, the order is not repaired.
    let mut unsorted = [Row::new([1, 0, 0], 0, 5.0), Row::new([2, 0, 0], 0, 1.0), Row::EMPTY];
    mlab_kernel::insert_with::<mlab::Unbiased, _>(&mut unsorted, Row::new([3, 0, 0], 0, 3.0));
    assert_eq!(
        unsorted,
        [
            Row::new([3, 0, 0], 0, 3.0),
            Row::new([2, 0, 0], 0, 1.0),
            Row::new([1, 0, 0], 0, 5.0)
        ]
    );
    // HT on a garbage head: the same bubble; the pushed-out row goes to the tail.
    let mut head = [Row::new([0, 0, 9], 0, nan)];
    let mut tail = Tail::EMPTY;
    hybrid::insert(&mut head, &mut tail, front);
    assert_eq!(head[0].color(), [0, 0, 9]);
    assert_eq!((tail.color_sum(), tail.alpha_sum(), tail.count()), ([10, 0, 0], 55, 1));
    assert_finite_in_range(
        mlab::Hybrid::<1, Paper>::from_parts(head, tail).resolve(),
        1.0 + 1023.0 / 255.0,
    );
}

#[test]
fn garbage_tail_read_back_from_bytes() {
    // Count 0 with non-zero sums resolves as count 1.
    let t = Tail::from_sums([1023, 0, 0], 0, 0);
    assert_eq!(
        t.resolve(),
        Resolved {
            color: Vec3::new(1023.0 * INV255, 0.0, 0.0),
            transmittance: 1.0
        }
    );
    // A mean alpha above 1 (alpha sum above 255 * count) is clamped to 1: opaque.
    let t = Tail::from_sums([255, 255, 255], 65535, 1);
    let r = t.resolve();
    assert_eq!(r.transmittance, 0.0);
    assert_finite_in_range(r, 1023.0 / 255.0);
    // Spare bits are ignored on read and kept on write.
    let mut t = Tail::from_bytes([0, 0, 0, 0xc0, 0, 0, 0, 0]);
    assert_eq!(t.resolve(), Resolved::CLEAR);
    t.add(Row::new([1, 2, 3], 250, 1.0));
    assert_eq!(mlab::Row::from_bytes(t.to_bytes()).words()[0] >> 30, 3); // the spare bits are kept
    assert_eq!(t.to_bytes(), [1, 0x08, 0x30, 0xc0, 5, 0, 1, 0]);
    // Every extreme of the fields resolves finite and in range.
    for w0 in [0, 0x3fff_ffff, u32::MAX] {
        for w1 in [0, 1, 0xffff, 0x0001_ffff, 0xffff_0000, 0xffff_0001, u32::MAX] {
            assert_finite_in_range(
                <Tail as mlab::TailFormat>::from_bytes(mlab::Row::from_words([w0, w1]).to_bytes()).resolve(),
                1023.0 / 255.0,
            );
        }
    }
}

#[test]
fn saturated_tail() {
    // 300 opaque white rows: color sums stop at 1023, alpha sum at 65535, nothing wraps.
    let mut t = Tail::EMPTY;
    for i in 0..300 {
        t.add(Row::new([255; 3], 0, i as f32));
    }
    assert_eq!((t.color_sum(), t.alpha_sum(), t.count()), ([1023; 3], 65535, 300));
    assert_finite_in_range(t.resolve(), 1023.0 / 255.0);
    // The count stops at 65535.
    let mut t = Tail::from_sums([0; 3], 0, 65535);
    t.add(Row::new([1, 0, 0], 255, 1.0));
    assert_eq!((t.count(), t.color_sum()[0]), (65535, 1));
    // Saturation keeps HT order independent: two orders of the same stream, same bytes.
    let frags: Vec<Fragment> = (0..40)
        .map(|i| Fragment::premultiplied(Vec3::splat(0.9), 0.95, i as f32).unwrap())
        .collect();
    let (mut a, mut b) = (Hybrid::<2, Paper>::new(), Hybrid::<2, Paper>::new());
    frags.iter().for_each(|f| a.insert(f));
    frags.iter().rev().for_each(|f| b.insert(f));
    assert_eq!(a, b);
    assert_eq!(a.tail().color_sum(), [1023; 3]);
}

#[test]
fn background_not_validated() {
    // Backgrounds are caller data, not validated: NaN propagates into the pixel; the RGBA8
    // writer maps NaN to 0 and clamps; the RGBA16F writer keeps NaN and infinities.
    let r = Resolved {
        color: Vec3::splat(0.5),
        transmittance: 0.0,
    };
    let p = r.pixel(Background::Opaque(Vec3::new(f32::NAN, f32::INFINITY, -5.0)));
    assert!(p.x.is_nan(), "NaN * 0 is NaN: {p:?}");
    assert!(p.y.is_nan(), "infinity * 0 is NaN: {p:?}");
    assert_eq!(p.z, 0.5);
    assert_eq!(to_rgba8(p), [0, 0, 128, 255]);
    let h = to_rgba16f(p);
    assert!(h[0].is_nan() && h[1].is_nan());
    let bright = Resolved {
        color: Vec3::splat(1e6),
        transmittance: 1.0,
    }
    .pixel(Background::Transparent);
    assert_eq!(to_rgba8(bright), [255, 255, 255, 0]);
    assert!(to_rgba16f(bright)[0].is_infinite());
}

// ---- Lanes ----------------------------------------------------------------------------

#[test]
fn lanes_invalid_fragments_and_off_lanes() {
    use mlab::lanes::{self, FragmentLanes, HybridSpan, LANES};
    // One bad input of each kind per lane; lane 7 is valid but off.
    let nan = f32::NAN;
    let frags = FragmentLanes {
        color: [
            [0.5, nan, f32::INFINITY, -0.5, 1.5, 0.5, 0.5, 0.5],
            [0.25; LANES],
            [0.0; LANES],
        ],
        alpha: [0.5, 0.5, 0.5, 0.5, 1.0, 2.0, 0.5, 0.5],
        depth: [1.0, 1.0, 1.0, 1.0, 1.0, 1.0, f32::INFINITY, 3.0],
        key: None,
    };
    let mask = 0b0111_1111;
    let q = frags.quantize_with::<Paper>(mask);
    assert_eq!((q.valid, q.invalid), (0b0000_0001, 0b0111_1110));
    for lane in 0..LANES {
        let c = Vec3::new(frags.color[0][lane], frags.color[1][lane], frags.color[2][lane]);
        let scalar = Fragment::premultiplied(c, frags.alpha[lane], frags.depth[lane]);
        assert_eq!(scalar.is_err(), q.invalid >> lane & 1 == 1, "lane {lane}: {scalar:?}");
    }
    // Invalid and off lanes are left untouched, whatever rows they are handed.
    let garbage = Row::from_bytes([0xab, 0xcd, 0xef, 1, 0xff, 0xff, 0xff, 0xff]);
    let mut span = [[garbage; LANES]; 2];
    span[0][0] = Row::EMPTY;
    span[1][0] = Row::EMPTY;
    lanes::mlab_insert_with::<Paper, 2>(&mut span, &q.rows, q.valid);
    assert_eq!(span[0][0], Row::new([128, 64, 0], 127, 1.0));
    assert!((1..LANES).all(|lane| span[0][lane] == garbage && span[1][lane] == garbage));
    let mut ht = HybridSpan::<1>::default();
    lanes::hybrid_insert(&mut ht, &[garbage; LANES], 0);
    assert_eq!(ht, HybridSpan::<1>::default());
}

#[test]
fn span_with_lanes_outside_the_buffer() {
    use mlab::SpanFramebuffer;
    use mlab::lanes::LANES;
    let (w, h) = (13, 2); // two spans per line, the second one partial (5 pixels, 3 padding lanes)
    let mut storage = vec![Row::EMPTY; SpanFramebuffer::<2>::rows_needed(w, h).unwrap()];
    assert_eq!(storage.len(), 2 * 8 * 2 * 2);
    let row = Row::new([9, 0, 0], 100, 1.0);
    let mut fb = SpanFramebuffer::<2>::new_cleared(&mut storage, w, h).unwrap();
    // Lane 4 of a span at x = 9 is x = 13, outside: the whole span is refused.
    let e = FbE::OutOfBounds {
        x: 13,
        y: 1,
        width: 13,
        height: 2,
    };
    assert_eq!(fb.insert_span(9, 1, &[row; LANES], 0b1_1111), Err(e));
    // A line outside is refused even with no lane on.
    assert_eq!(
        fb.insert_span(0, 2, &[row; LANES], 0),
        Err(FbE::OutOfBounds {
            x: 0,
            y: 2,
            width: 13,
            height: 2
        })
    );
    assert!(
        fb.as_rows().iter().all(|r| r.is_empty()),
        "a refused span changed the storage"
    );
    // The same span with the outside lane off: lanes 0..4 are written, nothing else.
    assert_eq!(fb.insert_span(9, 1, &[row; LANES], 0b1111), Ok(()));
    for x in 0..w {
        let want = if x >= 9 { [row, Row::EMPTY] } else { [Row::EMPTY; 2] };
        assert_eq!(fb.pixel(x, 1), Ok(want), "x = {x}");
    }
    assert_eq!(
        fb.as_rows().iter().filter(|r| !r.is_empty()).count(),
        4,
        "padding lanes written"
    );
    assert_eq!(
        fb.pixel(13, 1),
        Err(FbE::OutOfBounds {
            x: 13,
            y: 1,
            width: 13,
            height: 2
        })
    );
}

// ---- Findings: regression tests for fixed ones, reproducers (ignored) for open ones ----

/// F1 (fixed in d37150f): `Tail::resolve` amplified the tail's light above the documented
/// `[0, 1023/255]` (5.31 instead of 4.00) when the mean alpha was a few f32 ulps.
#[test]
fn finding_f1_tail_never_amplifies_light() {
    for count in [43690, 30000, 49418, 65535] {
        for alpha in [1, 2, 5] {
            let r = Tail::from_sums([1023; 3], alpha, count).resolve();
            assert!(
                r.color.max_element() <= 1023.0 * INV255,
                "count {count}, alpha {alpha}: {r:?}"
            );
        }
    }
    // The same tail from valid fragments: one faint fragment and 43689 additive ones.
    let mut h = Hybrid::<0, Paper>::new();
    h.insert(&Fragment::premultiplied(Vec3::ONE, 1.0 / 255.0, 0.0).unwrap());
    let light = Fragment::additive(Vec3::ONE, 1.0).unwrap();
    for _ in 1..43690 {
        h.insert(&light);
    }
    assert_eq!(
        (h.tail().color_sum(), h.tail().alpha_sum(), h.tail().count()),
        ([1023; 3], 1, 43690)
    );
    let exact = 1023.0 * (1.0 - (1.0 - 1.0 / (255.0 * 43690.0f64)).powf(43690.0));
    let px = h.resolve().over(Vec3::ZERO);
    assert!((f64::from(px.x) - exact).abs() < 0.01, "pixel {px:?}, exact {exact}");
}

/// F1b (fixed): the clamp of F1 removed the amplification, not the cancellation. When
/// `1 - mean` rounded *up* (mean alpha just under 1.5 f32 ulps of 1), `(1 - T_tail) / S_a`
/// was too small and the tail's light was dimmed by up to a third: tail `color [1023; 3],
/// alpha 1, count 45372` resolved to 2.76 instead of 4.00. The kernel now computes
/// `g = (1 - x^n) / (n (1 - x))` as `S_n / n`, with the geometric sum
/// `S_n = 1 + x + ... + x^(n-1)` built by the same binary exponentiation as `x^n`.
#[test]
fn finding_f1b_tail_light_not_dimmed() {
    for (alpha, count) in [
        (1u32, 45372u32),
        (1, 48),
        (1, 65535),
        (3, 30000),
        (255, 1000),
        (60000, 65535),
    ] {
        check_tail_light(alpha, count);
    }
}

fn check_tail_light(alpha: u32, count: u32) {
    let r = Tail::from_sums([1023; 3], alpha, count).resolve();
    let n = f64::from(count);
    let s_a = f64::from(alpha) / 255.0;
    let exact = 1023.0 / 255.0 * (1.0 - (1.0 - s_a / n).powf(n)) / s_a;
    let err = (f64::from(r.color.x) - exact).abs() / exact;
    assert!(
        err < 0.01,
        "tail color {} vs exact {exact}: {:.1}% off",
        r.color.x,
        100.0 * err
    );
}

/// The default tail (13-bit sums, 12-bit count) from arbitrary bytes: every extreme of
/// every field resolves finite and in range, like the paper's.
#[test]
fn wide_tail_from_arbitrary_bytes() {
    use mlab::Tail as WideTail;
    let max = 8191.0 / 255.0;
    for v in [
        0u64,
        1,
        u64::MAX,
        0x000f_ffff_ffff_ffff,
        0xfff0_0000_0000_0000,
        0x7f80_0000_0000_0000,
    ] {
        for shift in [0, 13, 26, 39, 53] {
            for t in [
                WideTail::from_bytes(v.to_le_bytes()),
                WideTail::from_bytes(v.rotate_left(shift).to_le_bytes()),
            ] {
                assert_finite_in_range(t.resolve(), max);
            }
        }
    }
    // Count 0 with non-zero sums resolves as count 1; a mean alpha above 1 is clamped.
    let t = WideTail::from_sums([8191, 0, 0], 0, 0);
    assert_eq!(t.resolve().transmittance, 1.0);
    let r = WideTail::from_sums([255; 3], 16383, 1).resolve();
    assert_eq!(r.transmittance, 0.0);
    assert_finite_in_range(r, max);
}

/// The default tail saturates without wrapping and stays order independent when it does.
#[test]
fn wide_tail_saturates() {
    use mlab::Tail as WideTail;
    let mut t = WideTail::EMPTY;
    for i in 0..70 {
        t.add(Row::new([255; 3], 0, i as f32));
    }
    assert_eq!((t.color_sum(), t.alpha_sum(), t.count()), ([8191; 3], 16383, 70));
    assert!(t.saturated());
    let mut t = WideTail::from_sums([0; 3], 0, 2047);
    t.add(Row::new([1, 0, 0], 255, 1.0));
    assert_eq!((t.count(), t.color_sum()[0]), (2047, 1));
    let frags: Vec<Fragment> = (0..60)
        .map(|i| Fragment::premultiplied(Vec3::splat(0.9), 0.95, i as f32).unwrap())
        .collect();
    let (mut a, mut b) = (Hybrid::<2>::new(), Hybrid::<2>::new());
    frags.iter().for_each(|f| a.insert(f));
    frags.iter().rev().for_each(|f| b.insert(f));
    assert_eq!(a, b);
    assert!(a.tail().saturated());
    // 200 fragments of alpha 0.03 saturate the paper's color sums, not the default tail.
    let faint: Vec<Fragment> = (0..200)
        .map(|i| Fragment::straight(Vec3::ONE, 0.03, i as f32).unwrap())
        .collect();
    let (mut wide, mut paper) = (Hybrid::<0>::new(), Hybrid::<0, Paper>::new());
    faint.iter().for_each(|f| {
        wide.insert(f);
        paper.insert(f)
    });
    assert!(paper.tail().saturated());
    assert!(!wide.tail().saturated());
}
