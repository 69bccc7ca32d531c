//! Checks shared by the targets. Each one panics (a libFuzzer crash) with a message that
//! names the broken property.

use mlab::{Arithmetic, Fragment, FragmentError, Paper, Resolved, Row, Unbiased};

use crate::defects::defects;
use crate::input::{Ctor, RawFragment};
use mlab_reference::model::{DITHERED_QUANT_ERROR, Model, is_faint, ref_fragment_hash, ref_key, ref_quantize_dithered};

/// Build the fragment with the kernel and check it against the defect model:
/// `Ok` exactly when the arguments have no defect, otherwise one of their defects, with
/// NaN reported first as documented; a valid fragment holds the given values bit for
/// bit and quantizes to the reference rows (see [`check_quantization`]). Returns the fragment when valid.
pub fn validate(raw: &RawFragment) -> Option<Fragment> {
    let got = raw.build();
    let (d, exp) = defects(raw);
    match got {
        Err(e) => {
            assert!(!d.is_empty(), "{raw:?}: rejected with {e:?} but has no defect");
            assert!(
                d.contains(e),
                "{raw:?}: rejected with {e:?}, which it does not have ({d:?})"
            );
            check_nan_first(raw, e);
            None
        }
        Ok(f) => {
            assert!(d.is_empty(), "{raw:?}: accepted as {f:?} but has defects {d:?}");
            let c = f.color().to_array();
            assert_eq!(
                c.map(f32::to_bits),
                exp.color.map(f32::to_bits),
                "{raw:?}: premultiplied color changed"
            );
            assert_eq!(f.alpha().to_bits(), exp.alpha.to_bits(), "{raw:?}: alpha changed");
            assert_eq!(f.depth().to_bits(), raw.z.to_bits(), "{raw:?}: depth changed");
            // The hash's pixel and a stable key from the input's bits: both seeds, any pixel.
            let pixel = raw.z.to_bits().rotate_left(11) ^ raw.a.to_bits();
            check_quantization(&f, pixel);
            check_quantization(&f.with_key(raw.color[0].to_bits() ^ pixel.rotate_left(3)), pixel);
            Some(f)
        }
    }
}

/// The documented order (kernel `Fragment::premultiplied` docs, since d37150f): NaN
/// (depth, alpha, color), then infinities (color, depth), then ranges (negative color,
/// alpha outside `[0, 1]`, premultiplied color above 1). `with_transmittance` checks its
/// transmittance argument (NaN, range) before anything else.
pub fn expected_error(raw: &RawFragment) -> Option<FragmentError> {
    let (c, a, z) = (raw.color, raw.a, raw.z);
    if raw.ctor == Ctor::WithTransmittance {
        if a.is_nan() {
            return Some(FragmentError::NanAlpha);
        }
        if !(0.0..=1.0).contains(&a) {
            return Some(FragmentError::AlphaOutOfRange);
        }
    }
    let alpha = if raw.ctor == Ctor::WithTransmittance {
        1.0 - a
    } else {
        a
    };
    let checks = [
        (z.is_nan(), FragmentError::NanDepth),
        (alpha.is_nan(), FragmentError::NanAlpha),
        (c.iter().any(|v| v.is_nan()), FragmentError::NanColor),
        (c.iter().any(|v| v.is_infinite()), FragmentError::InfiniteColor),
        (z.is_infinite(), FragmentError::InfiniteDepth),
        (c.iter().any(|&v| v < 0.0), FragmentError::NegativeColor),
        (!(0.0..=1.0).contains(&alpha), FragmentError::AlphaOutOfRange),
    ];
    if let Some(&(_, e)) = checks.iter().find(|(hit, _)| *hit) {
        return Some(e);
    }
    let pre = if raw.ctor == Ctor::Straight {
        c.map(|v| v * alpha)
    } else {
        c
    };
    pre.iter().any(|&v| v > 1.0).then_some(FragmentError::ColorAboveOne)
}

/// The error must be the first defect in the documented order.
fn check_nan_first(raw: &RawFragment, e: FragmentError) {
    assert_eq!(
        Some(e),
        expected_error(raw),
        "{raw:?}: not the first defect in the documented order"
    );
}

/// The rows of a valid fragment: `Paper::quantize` (to nearest) and `Unbiased::quantize`
/// (to nearest, dithered for faint fragments), each byte-equal to the reference quantization
/// of its arithmetic ([`Model::ref_quantize`]), the faint ones byte-equal to the reference
/// dithered quantization ([`ref_quantize_dithered`]); each checked with [`check_row`].
pub fn check_quantization(f: &Fragment, pixel: u32) {
    let (c, a, z) = (f.color().to_array(), f.alpha(), f.depth());
    let h = f.hash(pixel);
    assert_eq!(h, ref_fragment_hash(ref_key(f), pixel), "{f:?}: hash in pixel {pixel}");
    let paper = Paper::quantize(f, h);
    check_row(f, paper, Paper::ref_row(f, pixel), Paper::quant_error(a), Paper::NAME);
    let unbiased = Unbiased::quantize(f, h);
    check_row(
        f,
        unbiased,
        Unbiased::ref_row(f, pixel),
        Unbiased::quant_error(a),
        Unbiased::NAME,
    );
    if !is_faint(a) {
        assert_eq!(unbiased, paper, "{f:?}: not faint, but quantized unlike the paper's");
    } else {
        check_row(
            f,
            unbiased,
            ref_quantize_dithered(c, a, z, h),
            DITHERED_QUANT_ERROR,
            "dithered",
        );
    }
}

/// A row quantized from a valid fragment: byte-equal to the reference row `expected`;
/// each byte within `max_error` steps (half a step to nearest, `511/512` dithered), plus
/// f32 rounding, of the exact value; a value within `1/1024` step of a byte quantizes to
/// that byte (the dither lies in `[1/512, 511/512]`); depth bit for bit; and color bytes
/// not above `255 - T` when the premultiplied color does not exceed alpha.
pub fn check_row(f: &Fragment, row: Row, expected: Row, max_error: f64, name: &str) {
    let c = f.color().to_array();
    assert_eq!(row, expected, "{f:?}: {name} quantization differs from the reference");
    let bound = max_error + 1e-4;
    let check_byte = |byte: u8, v: f32, what: &str| {
        let exact = f64::from(v) * 255.0;
        let err = (f64::from(byte) - exact).abs();
        assert!(err <= bound, "{f:?} -> {row:?}: {name} {what} byte off by {err} steps");
        if (exact - exact.round()).abs() <= 1.0 / 1024.0 {
            assert_eq!(
                f64::from(byte),
                exact.round(),
                "{f:?} -> {row:?}: {name} {what} not exact"
            );
        }
    };
    for (byte, v) in row.color().into_iter().zip(c) {
        check_byte(byte, v, "color");
    }
    let opacity = 255 - row.transmittance();
    check_byte(opacity, f.alpha(), "alpha");
    assert_eq!(row.depth().to_bits(), f.depth().to_bits());
    assert!(!row.is_empty(), "{f:?}: a valid fragment became the empty row");
    if c.iter().all(|&v| v <= f.alpha()) {
        assert!(
            row.color().iter().all(|&b| b <= opacity),
            "{f:?} -> {row:?}: {name} color above alpha after quantization"
        );
    }
}

/// True if the rows satisfy the blending-array invariants (see [`check_invariants`]).
pub fn invariants_hold(rows: &[Row]) -> bool {
    mlab_reference::check_invariants(rows, false).is_ok()
}

/// Blending-array (and HT head) invariants ([`mlab_reference::check_invariants`]): no NaN
/// depth, depths non-decreasing front to back, rows at `z = +infinity` are exactly
/// [`Row::EMPTY`] (hence only at the back).
pub fn check_invariants(rows: &[Row], context: &dyn core::fmt::Debug) {
    if let Err(e) = mlab_reference::check_invariants(rows, false) {
        panic!("invariants broken: {e} after {context:?}");
    }
}

/// A resolved pixel: finite, transmittance in `[0, 1]`, color channels in `[0, max_color]`
/// up to f32 rounding (a few ulps: `1023 * (1/255)` in f32 is one ulp above `1023/255`).
pub fn check_resolved(r: Resolved, max_color: f32, context: &dyn core::fmt::Debug) {
    let max_color = max_color * (1.0 + 4.0 * f32::EPSILON);
    let t = r.transmittance;
    assert!(
        (0.0..=1.0).contains(&t),
        "transmittance {t} out of [0, 1]: {r:?} from {context:?}"
    );
    for c in r.color.to_array() {
        assert!(
            (0.0..=max_color).contains(&c),
            "color {c} out of [0, {max_color}]: {r:?} from {context:?}"
        );
    }
}

/// `|got - want| <= bound` for color channels and transmittance.
pub fn check_close(got: Resolved, want: ([f64; 3], f64), bound: f64, context: &dyn core::fmt::Debug) {
    for (i, (g, w)) in got.color.to_array().into_iter().zip(want.0).enumerate() {
        let err = (f64::from(g) - w).abs();
        assert!(
            err <= bound,
            "channel {i}: {got:?} vs exact {want:?}, error {err} > {bound}, from {context:?}"
        );
    }
    let err = (f64::from(got.transmittance) - want.1).abs();
    assert!(
        err <= bound,
        "transmittance: {got:?} vs exact {want:?}, error {err} > {bound}, from {context:?}"
    );
}

/// True if no two depths compare equal (`-0.0 == 0.0` counts as equal).
pub fn distinct_depths(rows: &[Row]) -> bool {
    let mut z: Vec<f32> = rows.iter().map(|r| r.depth()).collect();
    z.sort_by(|a, b| a.partial_cmp(b).expect("finite depths"));
    z.windows(2).all(|w| w[0] != w[1])
}
