//! Shared pieces of the `mlab` fuzz targets (issue 5): an input decoder, independent
//! reference models, and the checks. Each target in `fuzz_targets/` is one line that calls
//! a function of [`targets`], so the checks can also be replayed from a plain test.
//!
//! Every target checks a differential or an invariant, never only "no crash":
//!
//! | target | checks |
//! |---|---|
//! | `mlab_stream` | fragment validation against an independent defect model; after every insert: invariants, byte equality with a reference Listing 1 ([`reference::RefMlab`]), background visibility within `n/255` of the exact product; at the end, when the stream fits, the f64 oracle within `n/255` |
//! | `hybrid_stream` | the same validation; head and tail byte-equal to a sort-and-sum reference after every insert; bytes identical for a shuffled and a reversed stream (distinct depths); f64 oracle when the stream fits |
//! | `rows_from_bytes` | arbitrary rows and tails: layout round trips, resolve finite and in range and equal to an f64 composite, insert equal to a transcription of Listing 1 with an independent merge, tail saturation, invariants kept when they held before |
//! | `lanes_masks` | framebuffer spans with masks at the buffer edges: pixels that are off (or outside) never change, guard rows never change, errors change nothing, resolve equals the per-pixel resolve |
//!
//! Lanes: `mlab_stream`, `hybrid_stream` and `rows_from_bytes` also run every insert and
//! resolve through `mlab::lanes` (8 pixels, masks) and require byte-for-byte (rows, tails)
//! and bit-for-bit (resolved f32) equality with the scalar kernel.

pub mod check;
pub mod input;
pub mod reference;
pub mod targets;

/// The instruction set this fuzz build targets (`-C target-cpu`): printed once at start.
pub const BACKEND: &str = if cfg!(target_feature = "avx2") {
    "avx2"
} else if cfg!(target_feature = "sse2") {
    "sse2"
} else {
    "scalar"
};

/// Print which backend runs (called once by each target's `init`): the fuzz build's
/// instruction set and the kernel's lanes backend.
pub fn announce(target: &str) {
    eprintln!(
        "mlab_fuzz backend: {BACKEND}, lanes {} ({target})",
        mlab::lanes::BACKEND
    );
}
