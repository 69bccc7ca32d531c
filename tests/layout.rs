//! 9. Layout: rows and tails pinned to literal bytes; size and alignment asserted.

use mlab::TailFormat as _;
use mlab::hybrid::PaperTail;
use mlab::{Hybrid, Paper, Row, Tail};

#[test]
fn row_layout_is_pinned() {
    assert_eq!(core::mem::size_of::<Row>(), 8);
    assert_eq!(core::mem::align_of::<Row>(), 8);
    let row = Row::new([0x11, 0x22, 0x33], 0x44, f32::from_bits(0x8877_6655));
    assert_eq!(row.to_bytes(), [0x11, 0x22, 0x33, 0x44, 0x55, 0x66, 0x77, 0x88]);
    assert_eq!(
        bytemuck::bytes_of(&row),
        &[0x11, 0x22, 0x33, 0x44, 0x55, 0x66, 0x77, 0x88]
    );
    assert_eq!(row.words(), [0x4433_2211, 0x8877_6655]);
    assert_eq!(Row::from_words([0x4433_2211, 0x8877_6655]), row);
    assert_eq!(Row::from_bytes(row.to_bytes()), row);
    // The empty row: color 0, T = 255, z = +inf (0x7f800000 little-endian).
    assert_eq!(Row::EMPTY.to_bytes(), [0, 0, 0, 255, 0x00, 0x00, 0x80, 0x7f]);
    assert_eq!(Row::default(), Row::EMPTY);
    // Zeroed is opaque black at depth 0, not empty.
    assert_ne!(<Row as bytemuck::Zeroable>::zeroed(), Row::EMPTY);
}

#[test]
fn paper_tail_layout_is_pinned() {
    assert_eq!(core::mem::size_of::<PaperTail>(), 8);
    assert_eq!(core::mem::align_of::<PaperTail>(), 8);
    let t = PaperTail::from_sums([1023, 0x155, 1], 0xbeef, 0x1234);
    // word0 = R | G << 10 | B << 20, word1 = alpha | count << 16, little-endian.
    assert_eq!(
        mlab::Row::from_bytes(t.to_bytes()).words(),
        [1023 | 0x155 << 10 | 1 << 20, 0x1234_beef]
    );
    assert_eq!(t.to_bytes(), [0xff, 0x57, 0x15, 0x00, 0xef, 0xbe, 0x34, 0x12]);
    assert_eq!(bytemuck::bytes_of(&t), &t.to_bytes());
    assert_eq!(PaperTail::EMPTY.to_bytes(), [0; 8]);
    assert_eq!(PaperTail::from_bytes(t.to_bytes()), t);
    // Fields saturate at construction.
    assert_eq!(
        mlab::Row::from_bytes(PaperTail::from_sums([5000, 0, 0], 1 << 20, 1 << 20).to_bytes()).words(),
        [1023, 0xffff_ffff]
    );
}

#[test]
fn tail_layout_is_pinned() {
    assert_eq!(core::mem::size_of::<Tail>(), 8);
    assert_eq!(core::mem::align_of::<Tail>(), 8);
    // R = 0x1abc, G = 0x0155, B = 0x1001, alpha = 0x2fed, count = 0x587 as one LE u64:
    // R | G << 13 | B << 26 | alpha << 39 | count << 53.
    let t = Tail::from_sums([0x1abc, 0x155, 0x1001], 0x2fed, 0x587);
    assert_eq!(u64::from_le_bytes(t.to_bytes()), 0xb0f7_f6c0_042a_babc);
    assert_eq!(t.to_bytes(), [0xbc, 0xba, 0x2a, 0x04, 0xc0, 0xf6, 0xf7, 0xb0]);
    assert_eq!(mlab::Row::from_bytes(t.to_bytes()).words(), [0x042a_babc, 0xb0f7_f6c0]);
    assert_eq!(bytemuck::bytes_of(&t), &t.to_bytes());
    assert_eq!(Tail::EMPTY.to_bytes(), [0; 8]);
    assert_eq!(Tail::from_bytes(t.to_bytes()), t);
    assert_eq!(
        (t.color_sum(), t.alpha_sum(), t.count()),
        ([0x1abc, 0x155, 0x1001], 0x2fed, 0x587)
    );
    // Fields saturate at construction: 13-bit colors, 14-bit alpha, 11-bit count.
    assert_eq!(
        u64::from_le_bytes(Tail::from_sums([9000, 0, 0], 1 << 20, 1 << 20).to_bytes()),
        0xffff_ff80_0000_1fff
    );
    assert!(Tail::from_sums([0, 0, 8191], 0, 1).saturated());
    assert!(Tail::from_sums([0; 3], 16383, 1).saturated());
    assert!(Tail::from_sums([0; 3], 0, 2047).saturated());
    assert!(!Tail::from_sums([8190; 3], 16382, 2046).saturated());
}

#[test]
fn array_sizes() {
    assert_eq!(core::mem::size_of::<mlab::BlendingArray<4>>(), 32);
    assert_eq!(core::mem::size_of::<Hybrid<3>>(), 32);
    assert_eq!(core::mem::size_of::<Hybrid<3, Paper>>(), 32);
    assert_eq!(core::mem::size_of::<[Row; 8]>(), 64);
}

/// The documented reading of a byte (`b as f32 * INV255`, `INV255 = 1 / 255` rounded to
/// f32; docs/layout.md), for every byte: 0 and 255 exact, strictly increasing, within one
/// f32 ulp of `b / 255`, quantized back to the same byte (as a fragment's color is), and what
/// the resolve of a single row gives for its color and transmittance bytes, bit for bit.
#[test]
fn unorm_reads_every_byte_as_the_resolve_does() {
    const INV255: f32 = 1.0 / 255.0;
    let unorm = |b: u8| f32::from(b) * INV255;
    let quantize = |v: f32| {
        let f = mlab::Fragment::premultiplied(mlab::glam::Vec3::splat(v), 1.0, 1.0).expect("valid");
        <Paper as mlab::Arithmetic>::quantize(&f, 0).color()[0]
    };
    assert_eq!(unorm(0), 0.0);
    assert_eq!(unorm(255), 1.0);
    for b in 0..=255u8 {
        let v = unorm(b);
        assert_eq!(v.to_bits(), (f32::from(b) * INV255).to_bits(), "byte {b}");
        let exact = f64::from(b) / 255.0;
        let ulp = f64::from(f32::EPSILON) * exact.max(f64::from(f32::MIN_POSITIVE));
        assert!((f64::from(v) - exact).abs() <= ulp, "byte {b}: {v} vs {exact}");
        if b > 0 {
            assert!(v > unorm(b - 1), "byte {b} not above byte {}", b - 1);
        }
        assert_eq!(quantize(v), b, "byte {b} does not round-trip");
        let r = mlab::resolve_rows(&[Row::new([b, 255 - b, b / 2], b, 1.0)]);
        assert_eq!(
            r.color.to_array().map(f32::to_bits),
            [unorm(b), unorm(255 - b), unorm(b / 2)].map(f32::to_bits),
            "byte {b}: resolve color"
        );
        assert_eq!(r.transmittance.to_bits(), unorm(b).to_bits(), "byte {b}: resolve T");
    }
}
