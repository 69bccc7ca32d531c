//! Shared pieces of the `mlab` fuzz targets (issue 5): an input decoder, a defect model of
//! validation, and the checks, over the shared reference crate `mlab-reference`
//! (`reference/`: the reference models of both arithmetics, the exact oracle and its
//! bounds, the lanes-vs-scalar checks, also used by the kernel's tests and the lab). Each target in `fuzz_targets/` is one line that calls
//! a function of [`targets`], so the checks can also be replayed from a plain test.
//!
//! Every target checks a differential or an invariant, never only "no crash", and runs
//! every input in **both arithmetics** of the kernel: `Paper` (products and fragments
//! rounded to nearest, the paper's 10/10/10/16/16-bit tail) and `Unbiased` (the default:
//! dithered merge products, fragments to nearest except faint ones, `alpha * 255 < 16`,
//! which are dithered; the 13/13/13/14/11-bit tail), each against its own reference model
//! ([`mlab_reference::Model`], written from the kernel's documentation: the dither hashes, the
//! floor formulas, the faint threshold and the tail bit tables are re-derived, never
//! called). The dithered quantization of faint fragments is checked against its reference too.
//!
//! | target | checks (in both arithmetics) |
//! |---|---|
//! | `mlab_stream` | fragment validation against an independent defect model; each valid fragment's rows (both arithmetics, the faint ones against the reference dithered quantization) byte-equal to the reference quantizations (within 0.5 step to nearest, 511/512 dithered, exact bytes kept, color <= alpha kept); after every insert: invariants, byte equality with a reference Listing 1 ([`mlab_reference::model::RefMlab`]) using the arithmetic's reference merge, background visibility within `(sum q_i + r merges)/255` of the exact product (`q_i` the fragments' quantization errors, `r` = 0.5 paper, 1 unbiased); at the end, when the stream fits, the f64 oracle within `(2 sum q_i - min q_i)/255` |
//! | `hybrid_stream` | the same validation; head and tail byte-equal to a sort-and-sum reference packed in the arithmetic's tail layout after every insert; bytes identical for a shuffled and a reversed stream (distinct depths); f64 oracle when the stream fits |
//! | `rows_from_bytes` | arbitrary rows and tails: layout round trips of the row and of both tails (fields, `saturated`, `from_sums` against the reference bit tables), both merges byte-equal to the reference merges and within one rounding of the exact products, keeping `color <= 255 - T`; resolve finite and in range and equal to an f64 composite; insert equal to a transcription of Listing 1 with the reference merge; HT insert with field-by-field saturation in each layout; tail resolve against Bavoil-Myers in f64; invariants kept when they held before |
//! | `batch_stream` | the span batcher against per-pixel inserts into a twin framebuffer (both arrangements, MLAB and HT, compile-time and run-time sizes, both arithmetics): every push (fragments, arbitrary row bytes, pixels outside) returns what the per-pixel insert returns, `pending()` within the pushes since the last flush (0 where the batcher passes fragments through), storage byte-identical after every flush, drop and at the end |
//! | `lanes_masks` | framebuffer spans with masks at the buffer edges, in both arithmetics: pixels that are off (or outside) never change, guard rows never change, errors change nothing, pixels equal to the per-pixel reference insert, resolve equals the per-pixel resolve |
//!
//! Lanes: `mlab_stream`, `hybrid_stream` and `rows_from_bytes` also run every insert and
//! resolve through `mlab::lanes` (8 pixels, masks) and require byte-for-byte (rows, tails)
//! and bit-for-bit (resolved f32) equality with the scalar kernel, in both arithmetics
//! (`FragmentLanes::quantize_with` against the scalar and the reference quantization too).
//!
//! `cargo test --manifest-path fuzz/Cargo.toml` replays the committed seeds through every
//! target without libFuzzer; `cargo test -p mlab-reference` (root workspace) checks the
//! reference models against the literal examples of the kernel's documentation.

pub mod batch;
pub mod check;
pub mod defects;
pub mod input;
pub mod targets;

/// Print which lanes backend runs (called once by each target's `init`): the kernel's own
/// [`mlab::lanes::BACKEND`], which names the instruction set `wide` compiled to.
pub fn announce(target: &str) {
    eprintln!("mlab_fuzz backend: {} ({target})", mlab::lanes::BACKEND);
}
