//! Property 8: every bad-input class returns its error; framebuffers refuse bad sizes and
//! coordinates and change nothing when they do.

use mlab::Framebuffer;
use mlab::TailFormat as _;
use mlab::glam::{Vec3, Vec4};
use mlab::{
    Arithmetic, Background, Fragment, FragmentError as E, FramebufferError, HybridFramebuffer, MlabFramebuffer, Row,
};

#[test]
fn every_bad_fragment_class_is_rejected() {
    let ok = Vec3::splat(0.5);
    let cases: &[(Result<Fragment, E>, E)] = &[
        (
            Fragment::premultiplied(Vec3::new(f32::NAN, 0.0, 0.0), 0.5, 1.0),
            E::NanColor,
        ),
        (Fragment::premultiplied(ok, f32::NAN, 1.0), E::NanAlpha),
        (Fragment::premultiplied(ok, 0.5, f32::NAN), E::NanDepth),
        (Fragment::premultiplied(ok, 0.5, f32::INFINITY), E::InfiniteDepth),
        (Fragment::premultiplied(ok, 0.5, f32::NEG_INFINITY), E::InfiniteDepth),
        (Fragment::premultiplied(ok, -0.01, 1.0), E::AlphaOutOfRange),
        (Fragment::premultiplied(ok, 1.01, 1.0), E::AlphaOutOfRange),
        (Fragment::premultiplied(ok, f32::INFINITY, 1.0), E::AlphaOutOfRange),
        (
            Fragment::premultiplied(Vec3::new(0.0, -0.1, 0.0), 0.5, 1.0),
            E::NegativeColor,
        ),
        (
            Fragment::premultiplied(Vec3::new(0.0, 0.0, f32::INFINITY), 0.5, 1.0),
            E::InfiniteColor,
        ),
        (
            Fragment::premultiplied(Vec3::new(1.5, 0.0, 0.0), 1.0, 1.0),
            E::ColorAboveOne,
        ),
        (Fragment::straight(Vec3::new(3.0, 0.0, 0.0), 0.5, 1.0), E::ColorAboveOne),
        (
            Fragment::straight(Vec3::new(-1.0, 0.0, 0.0), 0.5, 1.0),
            E::NegativeColor,
        ),
        (Fragment::with_transmittance(ok, 1.5, 1.0), E::AlphaOutOfRange),
        (Fragment::with_transmittance(ok, f32::NAN, 1.0), E::NanAlpha),
        (Fragment::additive(Vec3::new(2.0, 0.0, 0.0), 1.0), E::ColorAboveOne),
        (
            Fragment::premultiplied_rgba([0.1, 0.1, 0.1, 2.0], 1.0),
            E::AlphaOutOfRange,
        ),
        // NaN is reported before any other class.
        (
            Fragment::premultiplied(Vec3::new(-1.0, 0.0, 0.0), 0.5, f32::NAN),
            E::NanDepth,
        ),
    ];
    for (i, (got, want)) in cases.iter().enumerate() {
        assert_eq!(got, &Err(*want), "case {i}");
    }
}

#[test]
fn valid_edge_fragments_are_accepted() {
    // Additive (alpha 0, color > 0), color above alpha, -0.0 depth, subnormal depth, negative depth.
    assert!(Fragment::premultiplied(Vec3::splat(0.3), 0.0, 1.0).is_ok());
    assert!(Fragment::premultiplied(Vec3::splat(0.9), 0.1, -0.0).is_ok());
    assert!(Fragment::premultiplied(Vec3::new(-0.0, 0.0, 1.0), 1.0, f32::from_bits(1)).is_ok());
    assert!(Fragment::straight(Vec3::splat(4.0), 0.25, -5.0).is_ok()); // HDR straight, premul = 1
    let f = Fragment::premultiplied(Vec3::splat(0.9), 0.1, -0.0).unwrap();
    assert_eq!(
        <mlab::Paper as mlab::Arithmetic>::quantize(&f, 0).depth().to_bits(),
        (-0.0f32).to_bits(),
        "depth stored bit for bit"
    );
}

#[test]
fn framebuffer_rejects_bad_storage_and_coordinates() {
    let mut s = vec![Row::EMPTY; 3 * 2 * 4 - 1];
    assert_eq!(
        MlabFramebuffer::<4>::new(&mut s, 3, 2).unwrap_err(),
        FramebufferError::StorageLength {
            expected: 24,
            actual: 23
        }
    );
    assert_eq!(
        MlabFramebuffer::<4>::new(&mut s, u32::MAX, u32::MAX).unwrap_err(),
        FramebufferError::SizeOverflow
    );
    assert_eq!(
        HybridFramebuffer::<3>::new(&mut s, 3, 2).unwrap_err(),
        FramebufferError::StorageLength {
            expected: 24,
            actual: 23
        }
    );
    let mut s = vec![Row::EMPTY; 24];
    let mut fb = MlabFramebuffer::<4>::new(&mut s, 3, 2).unwrap();
    let f = Fragment::straight(Vec3::ONE, 0.5, 1.0).unwrap();
    for (x, y) in [(3, 0), (0, 2), (u32::MAX, u32::MAX)] {
        assert_eq!(
            fb.insert(x, y, &f),
            Err(FramebufferError::OutOfBounds {
                x,
                y,
                width: 3,
                height: 2
            })
        );
        assert!(fb.pixel(x, y).is_err());
        assert!(fb.resolve(x, y).is_err());
    }
    assert!(fb.as_rows().iter().all(|r| r.is_empty()), "errors change nothing");
    let mut out = vec![[0u8; 4]; 5];
    assert_eq!(
        fb.resolve_rgba8(&mut out, Background::Transparent),
        Err(FramebufferError::OutputLength { expected: 6, actual: 5 })
    );
    assert!(out.iter().all(|p| *p == [0; 4]), "errors write nothing");
    let mut s = vec![Row::EMPTY; 24];
    let mut hb = HybridFramebuffer::<3>::new(&mut s, 3, 2).unwrap();
    assert!(hb.insert(3, 1, &f).is_err());
    assert!(hb.pixel(0, 2).is_err());
}

#[test]
fn framebuffers_insert_resolve_and_expose_bytes() {
    let mut s = vec![Row::zeroed_row(); 2 * 2 * 2];
    let mut fb = MlabFramebuffer::<2>::new(&mut s, 2, 2).unwrap();
    fb.clear();
    let f = Fragment::straight(Vec3::new(0.0, 1.0, 0.0), 0.5, 2.0).unwrap();
    fb.insert(1, 0, &f).unwrap();
    // The default arithmetic quantizes with its dither: 127.5 becomes 127 or 128.
    let row = mlab::Unbiased::quantize(&f, f.hash(1));
    let ([_, g, _], t) = (row.color(), row.transmittance());
    assert!(g == 127 || g == 128);
    assert_eq!(g, 255 - t, "color and alpha share the dither");
    assert_eq!(fb.pixel(1, 0).unwrap()[0], row);
    assert_eq!(fb.as_bytes().len(), 64);
    assert_eq!(&fb.as_bytes()[16..24], &row.to_bytes());
    assert_eq!(
        fb.as_words()[4],
        u32::from_le_bytes(row.to_bytes()[..4].try_into().unwrap())
    );
    let mut out = vec![Vec4::ZERO; 4];
    fb.resolve_into(&mut out, Background::Transparent).unwrap();
    let inv = 1.0f32 / 255.0;
    assert_eq!(out[1], Vec4::new(0.0, g as f32 * inv, 0.0, 1.0 - t as f32 * inv));
    assert_eq!(out[0], Vec4::ZERO);
    let mut half = vec![[mlab::half::f16::ZERO; 4]; 4];
    fb.resolve_rgba16f(&mut half, Background::Opaque(Vec3::ONE)).unwrap();
    assert_eq!(half[0].map(|h| h.to_f32()), [1.0; 4]);

    let mut s = vec![Row::EMPTY; 2 * 2 * 2];
    let mut hb = HybridFramebuffer::<1>::new(&mut s, 2, 2).unwrap();
    hb.clear();
    hb.insert(0, 1, &f).unwrap();
    hb.insert(0, 1, &f).unwrap();
    let (head, tail) = hb.pixel(0, 1).unwrap();
    assert_eq!(head, [row]);
    assert_eq!(
        (tail.count(), tail.alpha_sum(), tail.color_sum()),
        (1, 255 - t as u32, [0, g as u32, 0])
    );
    // The tail lives in the pixel's last row-sized slot.
    assert_eq!(&hb.as_bytes()[(2 * 2 + 1) * 8..(2 * 2 + 2) * 8], &tail.to_bytes());
}

trait Zeroed {
    fn zeroed_row() -> Row;
}
impl Zeroed for Row {
    fn zeroed_row() -> Row {
        bytemuck::Zeroable::zeroed()
    }
}
