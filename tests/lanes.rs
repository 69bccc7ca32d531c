//! Lanes against the scalar kernel: byte for byte, for any stream (valid fragments, arbitrary
//! rows read from bytes, masks), M in {1, 2, 3, 4, 8} and K in {1, 3, 7}, in both
//! arithmetics (Paper and Unbiased). No tolerances.
//!
//! Set `MLAB_EXPECT_BACKEND` to a `lanes::BACKEND` string (`sse2`, `avx2`, `neon`, ...) to make
//! `backend_is_the_expected_one` fail when the build did not pick that backend (CI does, for
//! every target it runs).

#![allow(clippy::needless_range_loop)] // lane-indexed loops mirror the per-lane scalar calls

mod common;

use mlab::glam::Vec3;
use mlab::lanes::{self, FragmentLanes, HybridSpan, LANES};
use mlab::{
    Arithmetic, Background, Fragment, Paper, Row, TailFormat, Unbiased, hybrid, mlab as listing1, resolve_rows,
    to_rgba8,
};
use proptest::prelude::*;

#[test]
fn backend_is_the_expected_one() {
    println!("mlab lanes backend: {}", lanes::BACKEND);
    if let Ok(want) = std::env::var("MLAB_EXPECT_BACKEND") {
        assert_eq!(lanes::BACKEND, want, "lanes were compiled for another backend");
    }
}

type Step = ([Row; LANES], u8);

const BACKGROUNDS: [Background; 3] = [
    Background::Transparent,
    Background::Opaque(Vec3::new(0.2, 0.5, 1.0)),
    Background::Opaque(Vec3::new(f32::NAN, f32::INFINITY, -1.0)),
];

fn bits(r: mlab::Resolved) -> [u32; 4] {
    let c = r.color.to_array().map(f32::to_bits);
    [c[0], c[1], c[2], r.transmittance.to_bits()]
}

/// Check resolved lanes against the scalar resolve of each pixel, bit for bit, and the
/// RGBA8 writers for several backgrounds.
fn check_resolved(got: &lanes::ResolvedLanes, want: &[mlab::Resolved; LANES]) -> Result<(), TestCaseError> {
    for lane in 0..LANES {
        let g = got.get(lane).expect("lane in range");
        prop_assert_eq!(bits(g), bits(want[lane]), "lane {} resolve", lane);
    }
    for bg in BACKGROUNDS {
        let rgba = got.rgba8(bg);
        let pixels = got.pixels(bg);
        for lane in 0..LANES {
            prop_assert_eq!(
                rgba[lane],
                to_rgba8(want[lane].pixel(bg)),
                "lane {} rgba8 {:?}",
                lane,
                bg
            );
            prop_assert_eq!(
                pixels[lane].to_array().map(f32::to_bits),
                want[lane].pixel(bg).to_array().map(f32::to_bits)
            );
        }
    }
    Ok(())
}

/// Run a stream through the MLAB lanes and through the scalar kernel per lane; compare
/// every byte after every step, then the resolve.
fn check_mlab<A: Arithmetic, const M: usize>(
    initial: &[[Row; M]; LANES],
    stream: &[Step],
) -> Result<(), TestCaseError> {
    let mut span = lanes::from_pixel_major(initial);
    prop_assert_eq!(&lanes::to_pixel_major(&span), initial, "lossless conversion");
    let mut pixels = *initial;
    for (rows, mask) in stream {
        lanes::mlab_insert_with::<A, M>(&mut span, rows, *mask);
        for lane in 0..LANES {
            if mask & (1 << lane) != 0 {
                listing1::insert_with::<A, M>(&mut pixels[lane], rows[lane]);
            }
        }
        prop_assert_eq!(
            &lanes::to_pixel_major(&span),
            &pixels,
            "{} M={} after mask {:08b}",
            A::NAME,
            M,
            mask
        );
    }
    let want = pixels.map(|p| resolve_rows(&p));
    for bg in BACKGROUNDS {
        prop_assert_eq!(
            lanes::mlab_resolve_rgba8(&span, bg),
            want.map(|r| to_rgba8(r.pixel(bg))),
            "M={} rgba8",
            M
        );
    }
    check_resolved(&lanes::mlab_resolve(&span), &want)
}

fn check_hybrid<const K: usize, A: Arithmetic>(
    initial: &HybridSpan<K, A>,
    stream: &[Step],
) -> Result<(), TestCaseError> {
    let mut span = *initial;
    let mut heads: [[Row; K]; LANES] = core::array::from_fn(|l| core::array::from_fn(|j| initial.head[j][l]));
    let mut tails = initial.tails;
    for (rows, mask) in stream {
        lanes::hybrid_insert(&mut span, rows, *mask);
        for lane in 0..LANES {
            if mask & (1 << lane) != 0 {
                hybrid::insert(&mut heads[lane], &mut tails[lane], rows[lane]);
            }
        }
        for lane in 0..LANES {
            for j in 0..K {
                prop_assert_eq!(
                    span.head[j][lane],
                    heads[lane][j],
                    "{} K={} head {} lane {}",
                    A::NAME,
                    K,
                    j,
                    lane
                );
            }
        }
        prop_assert_eq!(span.tails, tails, "{} K={} tails", A::NAME, K);
    }
    let want: [mlab::Resolved; LANES] = core::array::from_fn(|l| hybrid::resolve(&heads[l], tails[l]));
    for bg in BACKGROUNDS {
        prop_assert_eq!(
            lanes::hybrid_resolve_rgba8(&span, bg),
            want.map(|r| to_rgba8(r.pixel(bg))),
            "K={} rgba8",
            K
        );
    }
    check_resolved(&lanes::hybrid_resolve(&span), &want)
}

fn check_all(stream: &[Step], garbage: &[u64]) -> Result<(), TestCaseError> {
    check_arithmetic::<Paper>(stream, garbage)?;
    check_arithmetic::<Unbiased>(stream, garbage)
}

fn check_arithmetic<A: Arithmetic>(stream: &[Step], garbage: &[u64]) -> Result<(), TestCaseError> {
    // From empty arrays.
    check_mlab::<A, 1>(&[[Row::EMPTY; 1]; LANES], stream)?;
    check_mlab::<A, 2>(&[[Row::EMPTY; 2]; LANES], stream)?;
    check_mlab::<A, 3>(&[[Row::EMPTY; 3]; LANES], stream)?;
    check_mlab::<A, 4>(&[[Row::EMPTY; 4]; LANES], stream)?;
    check_mlab::<A, 8>(&[[Row::EMPTY; 8]; LANES], stream)?;
    check_hybrid::<1, A>(&HybridSpan::new(), stream)?;
    check_hybrid::<3, A>(&HybridSpan::new(), stream)?;
    check_hybrid::<7, A>(&HybridSpan::new(), stream)?;
    // From arbitrary bytes (as read back from a GPU buffer).
    let row = |i: usize| Row::from_bytes(garbage[i % garbage.len()].wrapping_mul(i as u64 + 1).to_le_bytes());
    let tail = |i: usize| A::Tail::from_bytes(garbage[(i + 7) % garbage.len()].rotate_left(i as u32).to_le_bytes());
    if !garbage.is_empty() {
        check_mlab::<A, 4>(
            &core::array::from_fn(|l| core::array::from_fn(|j| row(l * 4 + j))),
            stream,
        )?;
        check_mlab::<A, 1>(&core::array::from_fn(|l| [row(l)]), stream)?;
        let mut h = HybridSpan::<3, A>::new();
        h.head = core::array::from_fn(|j| core::array::from_fn(|l| row(100 + j * 8 + l)));
        h.tails = core::array::from_fn(tail);
        check_hybrid::<3, A>(&h, stream)?;
    }
    Ok(())
}

/// A row from a valid fragment, or (one in five) arbitrary bits: NaN depths, any T.
fn any_row() -> impl Strategy<Value = Row> {
    prop_oneof![
        4 => common::normal_fragment().prop_map(|f| f.row()),
        1 => common::additive_fragment().prop_map(|f| f.row()),
        1 => any::<u64>().prop_map(|b| Row::from_bytes(b.to_le_bytes())),
    ]
}

fn step() -> impl Strategy<Value = Step> {
    let mask = prop_oneof![Just(0u8), Just(0xff), Just(1), Just(0x80), any::<u8>(), any::<u8>()];
    (prop::array::uniform8(any_row()), mask)
}

proptest! {
    #[test]
    fn lanes_equal_scalar_byte_for_byte(
        stream in prop::collection::vec(step(), 0..=24),
        garbage in prop::collection::vec(any::<u64>(), 0..=8),
    ) {
        check_all(&stream, &garbage)?;
    }

    /// Validation and quantization in lanes agree with the scalar constructors lane by lane,
    /// for arbitrary f32 bit patterns.
    #[test]
    fn quantize_lanes_equals_scalar(
        raw in prop::array::uniform8((prop::array::uniform3(edge_f32()), edge_f32(), edge_f32())),
        mask in any::<u8>(),
    ) {
        let frags = FragmentLanes {
            color: core::array::from_fn(|c| core::array::from_fn(|l| raw[l].0[c])),
            alpha: raw.map(|r| r.1),
            depth: raw.map(|r| r.2),
        };
        for (straight, unbiased) in [(false, false), (true, false), (false, true), (true, true)] {
            let q = match (straight, unbiased) {
                (false, false) => frags.quantize_with::<Paper>(mask),
                (true, false) => frags.quantize_straight_with::<Paper>(mask),
                (false, true) => frags.quantize(mask),
                (true, true) => frags.quantize_straight(mask),
            };
            prop_assert_eq!(q.valid & q.invalid, 0);
            prop_assert_eq!(q.valid | q.invalid, mask);
            for lane in 0..LANES {
                let (c, a, z) = raw[lane];
                let scalar = if straight {
                    Fragment::straight(Vec3::from_array(c), a, z)
                } else {
                    Fragment::premultiplied(Vec3::from_array(c), a, z)
                };
                let on = mask & (1 << lane) != 0;
                match scalar {
                    Ok(f) if on => {
                        prop_assert!(q.valid & (1 << lane) != 0, "lane {} should be valid", lane);
                        let want = if unbiased { Unbiased::quantize(&f) } else { f.row() };
                        prop_assert_eq!(q.rows[lane], want);
                    }
                    Err(_) if on => prop_assert!(q.invalid & (1 << lane) != 0, "lane {} should be invalid", lane),
                    _ => prop_assert_eq!(q.rows[lane], Row::EMPTY),
                }
            }
        }
    }
}

/// f32 values around every validation edge, plus arbitrary bit patterns.
fn edge_f32() -> impl Strategy<Value = f32> {
    prop_oneof![
        3 => prop::sample::select(vec![
            0.0f32, -0.0, 1.0, 0.5, 1.0 + f32::EPSILON, 1.0 - f32::EPSILON / 2.0, -f32::MIN_POSITIVE,
            f32::from_bits(1), f32::NAN, -f32::NAN, f32::INFINITY, f32::NEG_INFINITY, f32::MAX, 2.0,
            0.5 / 255.0, 1.5 / 255.0,
        ]),
        3 => 0.0f32..=1.0,
        1 => any::<u32>().prop_map(f32::from_bits),
    ]
}

/// The seeded table of edge cases: equal depths, alpha 0 and 1, +-0.0 depth, subnormal
/// depths, masks with one lane, all lanes, none; each as a whole stream.
#[test]
fn edge_case_table() {
    let f = |c: f32, a: f32, z: f32| Fragment::premultiplied(Vec3::splat(c), a, z).expect("valid").row();
    let sub = f32::from_bits(1);
    let cases: Vec<(&str, Vec<Step>)> = vec![
        (
            "equal depths",
            (0..6).map(|i| ([f(0.1 * i as f32, 0.5, 1.0); 8], 0xff)).collect(),
        ),
        (
            "alpha 0 and 1",
            vec![
                ([f(0.3, 0.0, 2.0); 8], 0xff),
                ([f(0.2, 1.0, 3.0); 8], 0xff),
                ([f(0.0, 0.0, 1.0); 8], 0xff),
            ],
        ),
        (
            "+-0.0 depth",
            vec![
                ([f(0.2, 0.5, 0.0); 8], 0xff),
                ([f(0.4, 0.5, -0.0); 8], 0xff),
                ([f(0.6, 0.5, 0.0); 8], 0b1010_1010),
            ],
        ),
        (
            "subnormal depths",
            vec![
                ([f(0.2, 0.5, sub); 8], 0xff),
                ([f(0.3, 0.5, 0.0); 8], 0xff),
                ([f(0.4, 0.5, -sub); 8], 0xff),
            ],
        ),
        (
            "one lane",
            (0..8).map(|l| ([f(0.5, 0.5, l as f32); 8], 1u8 << l)).collect(),
        ),
        ("no lane", vec![([f(0.5, 0.5, 1.0); 8], 0); 3]),
        (
            "all lanes, many",
            (0..40)
                .map(|i| {
                    (
                        core::array::from_fn(|l| f(0.02 * l as f32, 0.3, ((i * 7 + l) % 11) as f32)),
                        0xff,
                    )
                })
                .collect(),
        ),
        (
            "saturating tail",
            (0..300)
                .map(|i| ([f(1.0, 1.0, 10.0 + (i % 3) as f32); 8], 0xff))
                .collect(),
        ),
    ];
    for (name, stream) in cases {
        check_all(&stream, &[0x7fc0_0000_0000_0000, 0xffff_ffff_ffff_ffff, 0])
            .unwrap_or_else(|e| panic!("{name}: {e}"));
    }
}
