//! Shared test helpers: the exact per-pixel oracle and stream strategies.
#![allow(dead_code)]

use mlab::glam::Vec3;
use mlab::{Arithmetic, Fragment, Row};
use proptest::prelude::*;

/// One unorm8 rounding: the largest error a single quantization or a single `round(a*b/255)`
/// can introduce, plus f32 slack (f32 multiply before rounding, f32 resolve).
pub const DELTA: f64 = 0.5 / 255.0 + 1e-6;

/// The same for the unbiased arithmetic: a dithered quantization `floor(x + u)` with `u` in
/// `[1/512, 511/512]` and a dithered product `floor((p + d) / 255)` with `d` in `0..=254`
/// are each off by less than one unit (`q - x` lies in `(-1, 1)`), twice the paper's bound.
pub const DELTA_UNBIASED: f64 = 1.0 / 255.0 + 1e-6;

/// The rounding bound of an arithmetic: [`DELTA`] for the paper's, [`DELTA_UNBIASED`] for
/// the dithered one.
pub fn delta<A: Arithmetic>() -> f64 {
    if A::NAME == "paper" { DELTA } else { DELTA_UNBIASED }
}

/// Exact composite of a fragment stream (the oracle): stable sort by depth with later
/// submission in front on ties, then front to back in f64 over `background`.
/// Returns the pixel color and the background visibility (product of 1 - alpha).
pub fn oracle(stream: &[Fragment], background: [f64; 3]) -> ([f64; 3], f64) {
    let (c, v, _) = oracle_with_bound(stream, background);
    (c, v)
}

/// Indices of `stream` in compositing order (front to back, later first on ties).
pub fn oracle_order(stream: &[Fragment]) -> Vec<usize> {
    let mut idx: Vec<usize> = (0..stream.len()).collect();
    idx.sort_by(|&a, &b| {
        stream[a]
            .depth()
            .partial_cmp(&stream[b].depth())
            .expect("valid fragments have finite depth")
            .then(b.cmp(&a))
    });
    idx
}

/// The oracle, plus the quantization bound per channel for an MLAB array with M >= n
/// rows (or an HT head with K >= n): composing quantized fragments `(p + dp, t + dt)` with
/// `|dp|, |dt| <= DELTA` front to back gives, by telescoping
/// `C_j' - C_j = dp_j + dt_j * C_(j+1) + t_j' * (C_(j+1)' - C_(j+1))`,
/// `|error| <= DELTA * sum_j (1 + C_(j+1))`, where `C_(j+1)` is the exact composite behind
/// fragment j (background included). For fragments whose color does not exceed alpha and a
/// background in [0, 1], `C_(j+1) <= 1`, so the bound is at most `2 n DELTA`.
pub fn oracle_with_bound(stream: &[Fragment], background: [f64; 3]) -> ([f64; 3], f64, [f64; 3]) {
    oracle_with_bound_delta(stream, background, DELTA)
}

/// [`oracle_with_bound`] for a rounding bound `delta` per quantization and per product.
pub fn oracle_with_bound_delta(stream: &[Fragment], background: [f64; 3], delta: f64) -> ([f64; 3], f64, [f64; 3]) {
    let order = oracle_order(stream);
    // Back to front: C = p + (1 - a) * C_behind, accumulating the bound.
    let mut c = background;
    let mut v = 1.0f64;
    let mut bound = [0.0f64; 3];
    for &i in order.iter().rev() {
        let f = &stream[i];
        let p = f.color().to_array().map(|x| x as f64);
        let t = 1.0 - f.alpha() as f64;
        for ch in 0..3 {
            bound[ch] += delta * (1.0 + c[ch]);
            c[ch] = p[ch] + t * c[ch];
        }
        v *= t;
    }
    (c, v, bound)
}

/// A fragment from straight color (premultiplied color never exceeds alpha).
pub fn straight(c: [f32; 3], a: f32, z: f32) -> Fragment {
    Fragment::straight(Vec3::from_array(c), a, z).expect("valid test fragment")
}

/// Alpha values with the edges 0 and 1 well represented.
pub fn alpha() -> impl Strategy<Value = f32> {
    prop_oneof![1 => Just(0.0f32), 1 => Just(1.0f32), 6 => 0.0f32..=1.0]
}

/// Depths: a few discrete values (ties, +-0) or a continuous range (negative included).
pub fn depth() -> impl Strategy<Value = f32> {
    prop_oneof![
        2 => prop::sample::select(vec![-0.0f32, 0.0, 1.0, 2.0, 3.0]),
        3 => -10.0f32..100.0,
    ]
}

/// A normal (non-additive) fragment from straight color.
pub fn normal_fragment() -> impl Strategy<Value = Fragment> {
    (prop::array::uniform3(0.0f32..=1.0), alpha(), depth()).prop_map(|(c, a, z)| straight(c, a, z))
}

/// Pure additive light (alpha 0), small enough that sums stay below 1 per channel.
pub fn additive_fragment() -> impl Strategy<Value = Fragment> {
    (prop::array::uniform3(0.0f32..=0.1), depth())
        .prop_map(|(c, z)| Fragment::additive(Vec3::from_array(c), z).expect("valid additive fragment"))
}

/// Invariants of a blending array or HT head after a stream of valid fragments: rows
/// sorted by non-decreasing depth; rows at +infinity are exactly empty and only at the
/// back; with `normal` (no additive light), color bytes never exceed `255 - T`.
pub fn check_invariants(rows: &[Row], normal: bool) -> Result<(), String> {
    let mut seen_empty = false;
    for (i, r) in rows.iter().enumerate() {
        let z = r.depth();
        if z.is_nan() {
            return Err(format!("row {i} has NaN depth: {r:?}"));
        }
        if z == f32::INFINITY {
            if !r.is_empty() {
                return Err(format!("row {i} at +inf is not empty: {r:?}"));
            }
            seen_empty = true;
        } else if seen_empty {
            return Err(format!("row {i} is not empty but follows an empty row: {rows:?}"));
        }
        if i > 0 && rows[i - 1].depth() > z {
            return Err(format!("rows {} and {i} are out of order: {rows:?}", i - 1));
        }
        if normal {
            let coverage = 255 - r.transmittance();
            if r.color().iter().any(|&c| c > coverage) {
                return Err(format!("row {i} has color above its coverage: {r:?}"));
            }
        }
    }
    Ok(())
}

/// Max absolute channel difference.
pub fn max_diff(a: [f64; 3], b: [f64; 3]) -> f64 {
    (0..3).map(|i| (a[i] - b[i]).abs()).fold(0.0, f64::max)
}
