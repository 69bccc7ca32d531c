//! Shared test helpers: stream strategies and the blending-array invariants. The exact
//! per-pixel oracle, its bounds and the reference arithmetic live in `mlab-reference`
//! (`reference/`), shared with the fuzz targets and the lab.
#![allow(dead_code)]

use mlab::glam::Vec3;
use mlab::{Fragment, Row};
use proptest::prelude::*;

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
