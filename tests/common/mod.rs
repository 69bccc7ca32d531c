//! Shared test helpers: stream strategies and the blending-array invariants. The exact
//! per-pixel oracle, its bounds and the reference arithmetic live in `mlab-reference`
//! (`reference/`), shared with the fuzz targets and the lab.
#![allow(dead_code)]

use mlab::Fragment;
use mlab::glam::Vec3;
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

#[allow(unused_imports)] // not every test file checks invariants
pub use mlab_reference::check_invariants;

/// Max absolute channel difference.
pub fn max_diff(a: [f64; 3], b: [f64; 3]) -> f64 {
    (0..3).map(|i| (a[i] - b[i]).abs()).fold(0.0, f64::max)
}
