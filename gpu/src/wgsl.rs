//! The WGSL twin of the kernel, as source text for a renderer's own shaders.
//!
//! Every function works on the kernel's bytes: a row is a `vec2<u32>` holding
//! [`Row::words`](mlab::Row::words) (`x = R | G << 8 | B << 16 | T << 24`, `y` = the bits of the
//! f32 depth), a tail is a `vec2<u32>` holding the tail's two little-endian words. Fragments are
//! passed as the bit patterns of their f32 fields (`bitcast<u32>(v)`), premultiplied color,
//! alpha and depth, already validated as [`mlab::Fragment`] validates them (finite, color and
//! alpha in `[0, 1]`): the shader does not re-check. Quantization and merges take the
//! fragment's hash `h = mlab_fragment_hash(key, pixel)` ([`mlab::fragment_hash`]), which
//! seeds [`mlab::Unbiased`]'s dithers: `key` is the fragment's stable key
//! ([`mlab::Fragment::with_key`], the primitive's id) or, without one,
//! `mlab_content_key(c, a, z)` (the XOR of the five f32 bit patterns, as
//! [`mlab::Fragment::hash`]); `pixel` is the framebuffer's pixel id, `y * width + x`.
//!
//! No f32 arithmetic is used: the kernel's two f32 steps (the quantization `floor(v * 255 + u)`
//! and the faint test `alpha * 255 < 16`) are exact integer emulations of the correctly rounded
//! f32 multiply and add, and depths are compared by their bits, so FMA contraction and flushed
//! subnormals cannot change a byte (`docs/gpu.md` says why this is needed).
//!
//! | text | what | uses |
//! |---|---|---|
//! | [`KERNEL`] | quantization (both arithmetics), both merges, both tail adds, the depth test | nothing |
//! | [`mlab()`] | [`KERNEL`], a header for `M` and the arithmetic, `mlab_insert` (Listing 1) | |
//! | [`hybrid()`] | [`KERNEL`], a header for `K` and the arithmetic, `ht_insert` (Listing 2), `ht_resolve_rgba8` | |
//! | [`compositor()`] | [`mlab()`] or [`hybrid()`] followed by the compositor's entry point and bindings | [`crate::Compositor`] |
//! | [`SORT`] | the compositor's stable sort by pixel (a module of its own) | [`crate::Compositor`] |
//!
//! A shader includes [`mlab()`] (or [`hybrid()`]) and calls, per fragment:
//!
//! ```wgsl
//! var rows: array<vec2<u32>, MLAB_M>;           // the pixel's rows, loaded from storage
//! let c = vec3<u32>(bitcast<u32>(r), bitcast<u32>(g), bitcast<u32>(b));
//! let a = bitcast<u32>(alpha);
//! let z = bitcast<u32>(depth);
//! let h = mlab_fragment_hash(primitive_key, y * width + x); // or mlab_content_key(c, a, z)
//! mlab_insert(&rows, mlab_quantize(c, a, z, h), h); // Listing 1, then store the rows back
//! ```
//!
//! (HT: `ht_insert(&head, &tail, mlab_quantize(c, a, z, h))`; HT's insert has no merge.)
//!
//! Every name the text defines starts with `mlab_`, `ht_` or `composite_` (and the constants
//! `MLAB_M`, `HT_K`, `MLAB_EMPTY_ROW`, `MLAB_EMPTY_TAIL`). One method and size per shader module.

use crate::error::GpuError;
use mlab::{ArithKind, Layers};

/// The functions shared by every method: depth test, the fragment hash (`mlab_lowbias32`,
/// `mlab_fragment_hash`, `mlab_content_key`, `mlab_row_hash`), the exact f32 emulation,
/// quantization (`mlab_quantize_paper`, `mlab_quantize_unbiased`: `(c, a, z, h)`), merges
/// (`mlab_merge_paper`, `mlab_merge_unbiased`: `(front, back, h)`; Unbiased's depth is
/// `mlab_centroid_depth`), tail adds (`mlab_tail_add_paper`, `mlab_tail_add_wide`) and the
/// integer resolve's `mlab_q15` and `mlab_resolve_pixel`.
pub const KERNEL: &str = include_str!("wgsl/kernel.wgsl");

/// Listing 1 (`mlab_insert`) and the integer RGBA8 resolve (`mlab_resolve_rgba8`); needs `MLAB_M`, `mlab_merge` and [`KERNEL`] ([`mlab()`] has them all).
pub const MLAB_INSERT: &str = include_str!("wgsl/mlab.wgsl");

/// Listing 2 (`ht_insert`); needs `HT_K`, `ht_tail_add` and [`KERNEL`] ([`hybrid()`] has them all).
pub const HT_INSERT: &str = include_str!("wgsl/ht.wgsl");

/// The integer RGBA8 resolve of HT (`docs/layout.md`, "Integer resolve of HT"): the tail
/// decoders `ht_tail_fields_paper` and `ht_tail_fields_wide` (both return the struct
/// `ht_fields`: three color sums, alpha sum, count), the rounded Q16 product `mlab_q16`, its
/// Horner sums `ht_horner(coefficients, x)` (an `array<u32, 8>`, lowest first, written out), the
/// tail's `(T, g)` in Q16 (`ht_tail_resolve(alpha, count) -> vec2<u32>`, which uses nothing
/// but `mlab_q16` and `ht_horner`), and `ht_resolve_rgba8(&head, tail, background)` (the bytes
/// of the kernel's `resolve_rgba8` pixel as `R | G << 8 | B << 16 | A << 24`), which needs
/// `HT_K`, `ht_tail_fields` and [`KERNEL`] ([`hybrid()`] has them all). The background is the
/// `vec4<u32>` of [`crate::background_q15`], computed on the CPU.
pub const HT_RESOLVE: &str = include_str!("wgsl/ht_resolve.wgsl");

/// The compositor's sort by pixel ([`crate::Sort::Gpu`]), a module of its own: a bitonic sort
/// of `(stored pixel, submission index)` pairs (unique keys: the stable order), entry points
/// `sort_init`, `sort_step` (one compare-exchange per invocation) and `sort_offsets_of` (a
/// binary search per pixel); binding layout at the top of the text and in `docs/gpu.md`.
pub const SORT: &str = include_str!("wgsl/sort.wgsl");

/// The compositor's bindings, helpers and entry points (`composite`, `resolve`; see
/// [`compositor()`]), then a method's pair of texts: the `composite_pixel` (MLAB, HT) and the
/// `composite_resolve_pixel` (MLAB, HT) that the entry points call.
const COMPOSITE: &str = include_str!("wgsl/composite.wgsl");
const COMPOSITE_MLAB: &str = include_str!("wgsl/composite_mlab.wgsl");
const COMPOSITE_HT: &str = include_str!("wgsl/composite_ht.wgsl");
const COMPOSITE_RESOLVE: &str = include_str!("wgsl/composite_resolve.wgsl");
const COMPOSITE_RESOLVE_HT: &str = include_str!("wgsl/composite_resolve_ht.wgsl");

fn check_size(layers: Layers) -> Result<(), GpuError> {
    let (Layers::Mlab(n) | Layers::Hybrid(n)) = layers;
    if Layers::SIZES.contains(&n) {
        Ok(())
    } else {
        Err(GpuError::UnsupportedLayers(layers))
    }
}

/// MLAB with `m` rows in the arithmetic `arith`: [`KERNEL`], then `const MLAB_M`,
/// `mlab_merge` and `mlab_quantize` (the arithmetic's), then [`MLAB_INSERT`] (`mlab_insert`,
/// and `mlab_resolve_rgba8`, the kernel's integer RGBA8 resolve). `m` is one of
/// [`Layers::SIZES`] (the kernel's run-time sizes, 1..=8).
pub fn mlab(m: usize, arith: ArithKind) -> Result<String, GpuError> {
    check_size(Layers::Mlab(m))?;
    let a = arith.name();
    Ok(format!(
        "{KERNEL}\n// mlab_gpu::wgsl::mlab({m}, {a})\nconst MLAB_M: u32 = {m}u;\n\
         fn mlab_merge(front: vec2<u32>, back: vec2<u32>, h: u32) -> vec2<u32> {{\n    return mlab_merge_{a}(front, back, h);\n}}\n\
         fn mlab_quantize(c: vec3<u32>, a: u32, z: u32, h: u32) -> vec2<u32> {{\n    return mlab_quantize_{a}(c, a, z, h);\n}}\n\n{MLAB_INSERT}"
    ))
}

/// Hybrid Transparency with `k` head rows in the arithmetic `arith` ([`ArithKind::Paper`]: the
/// paper's tail, [`ArithKind::Unbiased`]: the 64-bit [`mlab::Tail`] as two words): [`KERNEL`],
/// then `const HT_K`, `ht_tail_add`, `ht_tail_fields` (the tail's decoder) and
/// `mlab_quantize`, then [`HT_INSERT`] (`ht_insert`) and [`HT_RESOLVE`] (`ht_resolve_rgba8`,
/// the kernel's integer RGBA8 resolve of HT). `k` is one of [`Layers::SIZES`].
pub fn hybrid(k: usize, arith: ArithKind) -> Result<String, GpuError> {
    check_size(Layers::Hybrid(k))?;
    let a = arith.name();
    let tail = match arith {
        ArithKind::Paper => "paper",
        ArithKind::Unbiased => "wide",
    };
    Ok(format!(
        "{KERNEL}\n// mlab_gpu::wgsl::hybrid({k}, {a})\nconst HT_K: u32 = {k}u;\n\
         fn ht_tail_add(tail: vec2<u32>, row: vec2<u32>) -> vec2<u32> {{\n    return mlab_tail_add_{tail}(tail, row);\n}}\n\
         fn ht_tail_fields(tail: vec2<u32>) -> ht_fields {{\n    return ht_tail_fields_{tail}(tail);\n}}\n\
         fn mlab_quantize(c: vec3<u32>, a: u32, z: u32, h: u32) -> vec2<u32> {{\n    return mlab_quantize_{a}(c, a, z, h);\n}}\n\n{HT_INSERT}\n{HT_RESOLVE}"
    ))
}

/// [`mlab()`] or [`hybrid()`] for `layers`, then the compositor's bindings and its entry point
/// `composite` (binding layout in `docs/gpu.md` and at the top of that text): the exact source
/// that [`crate::Compositor`] compiles ([`crate::Compositor::source`]).
pub fn compositor(layers: Layers, arith: ArithKind) -> Result<String, GpuError> {
    Ok(match layers {
        Layers::Mlab(m) => format!("{}\n{COMPOSITE}{COMPOSITE_MLAB}{COMPOSITE_RESOLVE}", mlab(m, arith)?),
        Layers::Hybrid(k) => format!("{}\n{COMPOSITE}{COMPOSITE_HT}{COMPOSITE_RESOLVE_HT}", hybrid(k, arith)?),
    })
}
