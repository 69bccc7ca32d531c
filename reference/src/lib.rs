//! `mlab-reference`: the one reference that the kernel's tests, the fuzz targets and the
//! evaluation tool (oit-lab) check the kernel against, kept apart from the kernel the way
//! BLAKE3 keeps its `reference_impl`: small, plain, written from the documentation.
//!
//! - [`oracle`]: the exact per-pixel composite (every fragment, sorted front to back, later
//!   submission in front on equal depth, f64), and the bounds that relate it to the
//!   kernel's quantized result ([`oracle::oracle_with_bound`], [`oracle::multilinear_bound`],
//!   [`oracle::visibility_bound`]).
//! - [`model`]: reference models of the kernel's two arithmetics ([`Model`], implemented for
//!   [`mlab::Paper`] and [`mlab::Unbiased`]): quantization, dithers, merge products, a
//!   `Vec`-based Listing 1, the HT tail layouts and a sort-and-sum Hybrid Transparency.
//! - [`check_invariants`]: the blending-array invariants, for the tests and the fuzz targets.
//! - [`lanes`]: the lanes-vs-scalar checks (the only part that calls the kernel's code, on
//!   both sides of each comparison).
//! - [`kind`]: the reference side of a pixel kind ([`RefKind`], [`MlabKind`], [`HtKind`]):
//!   one pixel's slots inserted into, resolved and cleared by the reference, for the fuzz
//!   targets and the framebuffer tests (its resolves and lanes insert call the kernel's, the
//!   side the framebuffers are compared with).
//!
//! The oracle and the models use the kernel's types (`Row`, `Fragment`) for input and
//! output only, and never call its arithmetic: every formula is re-derived from
//! `src/arith.rs`, `src/unorm.rs`, the tail tables of `src/tail.rs`, `docs/algorithm.md` and
//! `docs/layout.md`, and the models are checked against the literal examples of those docs
//! (`cargo test -p mlab-reference`), so that a reference cannot drift along with the kernel.
//!
//! What it replaced (issue 13 item 6): the exact oracle in `tests/common/mod.rs`
//! (`oracle`, `oracle_order`, `oracle_with_bound(_delta)`), `fuzz/src/reference.rs`
//! (`oracle`, `sort_front_to_back`), `lab/src/methods.rs` (`reference`'s composite),
//! `examples/rasterizer.rs` (`composite`); the reference merge and dither of
//! `tests/unbiased.rs`; the lanes checks of `tests/lanes.rs` and `fuzz/src/targets.rs` (now `fuzz/src/targets/`).
//! `examples/quickstart.rs` keeps its few lines so that it stands alone.

pub mod kind;
pub mod lanes;
pub mod model;
pub mod oracle;
pub mod resolve_int;
pub mod rng;

pub use kind::{HtKind, MlabKind, RefKind};
pub use model::Model;
pub use oracle::{DELTA, DELTA_UNBIASED, Layer, oracle, oracle_with_bound};
pub use rng::Rng;

use mlab::Row;

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
