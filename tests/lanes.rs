//! Lanes against the scalar kernel: byte for byte, for any stream (valid fragments, arbitrary
//! rows read from bytes, masks), M in {1, 2, 3, 4, 8} and K in {1, 3, 7}, in both
//! arithmetics (Paper and Unbiased). No tolerances. The checks themselves are
//! `mlab_reference::lanes` (`reference/`), which the fuzz targets run too.
//!
//! Set `MLAB_EXPECT_BACKEND` to a `lanes::BACKEND` string (`sse2`, `avx2`, `neon`, ...) to make
//! `backend_is_the_expected_one` fail when the build did not pick that backend (CI does, for
//! every target it runs).

#![allow(clippy::needless_range_loop)] // lane-indexed loops mirror the per-lane scalar calls

mod common;

use mlab::glam::Vec3;
use mlab::lanes::{self, HybridSpan, LANES};
use mlab::{Fragment, Hybrid, Paper, Row, TailFormat, Unbiased, hybrid, mlab as listing1};
use mlab_reference::Model;
use mlab_reference::lanes::{
    check_fragment_lanes, check_hybrid_rows, check_hybrid_span, check_mlab_rows, check_mlab_span,
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

/// A check of `mlab_reference::lanes` as a proptest failure, with what was running.
fn fail(context: String) -> impl FnOnce(String) -> TestCaseError {
    move |e| TestCaseError::fail(format!("{context}: {e}"))
}

/// Run a stream through the MLAB lanes and through the scalar kernel per lane; compare
/// every byte after every step, then the resolve (`mlab_reference::lanes::check_mlab_span`:
/// bit for bit, RGBA8 and pixels on every background).
fn check_mlab<A: Model, const M: usize>(initial: &[[Row; M]; LANES], stream: &[Step]) -> Result<(), TestCaseError> {
    let mut span = from_pixel_major(initial);
    prop_assert_eq!(&to_pixel_major(&span), initial, "lossless conversion");
    let mut pixels = *initial;
    for (rows, mask) in stream {
        lanes::mlab_insert_with::<A, M>(&mut span, rows, *mask);
        for lane in 0..LANES {
            if mask & (1 << lane) != 0 {
                listing1::insert_with::<A, M>(&mut pixels[lane], rows[lane]);
            }
        }
        check_mlab_rows(&span, &pixels).map_err(fail(format!("{} after mask {mask:08b}", A::NAME)))?;
    }
    check_mlab_span(&span, &pixels).map_err(fail(format!("{} M={M} resolve", A::NAME)))
}

/// The same for HT: the scalar side through `hybrid::insert` on each lane's head and tail.
fn check_hybrid<const K: usize, A: Model>(initial: &HybridSpan<K, A>, stream: &[Step]) -> Result<(), TestCaseError> {
    let mut span = *initial;
    let mut heads: [[Row; K]; LANES] = core::array::from_fn(|l| core::array::from_fn(|j| initial.head[j][l]));
    let mut tails = initial.tails;
    let pixels = |heads: &[[Row; K]; LANES], tails: &[A::Tail; LANES]| -> [Hybrid<K, A>; LANES] {
        core::array::from_fn(|l| Hybrid::from_parts(heads[l], tails[l]))
    };
    for (rows, mask) in stream {
        lanes::hybrid_insert(&mut span, rows, *mask);
        for lane in 0..LANES {
            if mask & (1 << lane) != 0 {
                hybrid::insert(&mut heads[lane], &mut tails[lane], rows[lane]);
            }
        }
        check_hybrid_rows(&span, &pixels(&heads, &tails)).map_err(fail(format!("after mask {mask:08b}")))?;
    }
    check_hybrid_span(&span, &pixels(&heads, &tails)).map_err(fail(format!("{} K={K} resolve", A::NAME)))
}

fn check_all(stream: &[Step], garbage: &[u64]) -> Result<(), TestCaseError> {
    check_arithmetic::<Paper>(stream, garbage)?;
    check_arithmetic::<Unbiased>(stream, garbage)
}

fn check_arithmetic<A: Model>(stream: &[Step], garbage: &[u64]) -> Result<(), TestCaseError> {
    // From empty arrays.
    check_mlab::<A, 1>(&[[Row::EMPTY; 1]; LANES], stream)?;
    check_mlab::<A, 2>(&[[Row::EMPTY; 2]; LANES], stream)?;
    check_mlab::<A, 3>(&[[Row::EMPTY; 3]; LANES], stream)?;
    check_mlab::<A, 4>(&[[Row::EMPTY; 4]; LANES], stream)?;
    check_mlab::<A, 8>(&[[Row::EMPTY; 8]; LANES], stream)?;
    check_hybrid::<1, A>(&HybridSpan::default(), stream)?;
    check_hybrid::<3, A>(&HybridSpan::default(), stream)?;
    check_hybrid::<7, A>(&HybridSpan::default(), stream)?;
    // From arbitrary bytes (as read back from a GPU buffer).
    let row = |i: usize| Row::from_bytes(garbage[i % garbage.len()].wrapping_mul(i as u64 + 1).to_le_bytes());
    let tail = |i: usize| A::Tail::from_bytes(garbage[(i + 7) % garbage.len()].rotate_left(i as u32).to_le_bytes());
    if !garbage.is_empty() {
        check_mlab::<A, 4>(
            &core::array::from_fn(|l| core::array::from_fn(|j| row(l * 4 + j))),
            stream,
        )?;
        check_mlab::<A, 1>(&core::array::from_fn(|l| [row(l)]), stream)?;
        let h = HybridSpan::<3, A> {
            head: core::array::from_fn(|j| core::array::from_fn(|l| row(100 + j * 8 + l))),
            tails: core::array::from_fn(tail),
        };
        check_hybrid::<3, A>(&h, stream)?;
    }
    Ok(())
}

/// A row from a valid fragment, or (one in five) arbitrary bits: NaN depths, any T.
fn any_row() -> impl Strategy<Value = Row> {
    prop_oneof![
        4 => common::normal_fragment().prop_map(|f| <mlab::Paper as mlab::Arithmetic>::quantize(&f, 0)),
        1 => common::additive_fragment().prop_map(|f| <mlab::Paper as mlab::Arithmetic>::quantize(&f, 0)),
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
    /// for arbitrary f32 bit patterns, premultiplied and straight, in both arithmetics; the
    /// rows equal the reference quantization too; `mlab_insert_fragments(_with)` and
    /// `hybrid_insert_fragments` insert exactly the valid lanes
    /// (`mlab_reference::lanes::check_fragment_lanes`).
    #[test]
    fn quantize_lanes_equals_scalar(
        raw in prop::array::uniform8((prop::array::uniform3(edge_f32()), edge_f32(), edge_f32())),
        mask in any::<u8>(),
    ) {
        check_fragment_lanes::<Paper>(&raw, mask).map_err(fail("paper".into()))?;
        check_fragment_lanes::<Unbiased>(&raw, mask).map_err(fail("unbiased".into()))?;
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
    let f = |c: f32, a: f32, z: f32| {
        <mlab::Paper as mlab::Arithmetic>::quantize(&Fragment::premultiplied(Vec3::splat(c), a, z).expect("valid"), 0)
    };
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

/// The span in the per-pixel arrangement, `[pixel][row]` (a transpose).
fn to_pixel_major<const M: usize>(span: &[[Row; LANES]; M]) -> [[Row; M]; LANES] {
    core::array::from_fn(|lane| core::array::from_fn(|j| span[j][lane]))
}

/// The inverse of [`to_pixel_major`].
#[allow(dead_code)]
fn from_pixel_major<const M: usize>(pixels: &[[Row; M]; LANES]) -> [[Row; LANES]; M] {
    core::array::from_fn(|j| core::array::from_fn(|lane| pixels[lane][j]))
}
