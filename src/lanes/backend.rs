//! Every instruction-set choice of the lanes in one place: what `wide` was compiled for and
//! the choices measured per instruction set (`docs/performance.md`). Two choices are `cfg`s,
//! because they pick a type or a module: Listing 2's rows (`w512` with AVX-512 F and BW, in
//! `lanes/mod.rs`) and MLAB's integer resolve (`resolve_int/`: SSE2 or SSSE3 form).

/// The SIMD instruction set `wide` compiled the lanes for, chosen at compile time:
///
/// - `"avx512"`: a build with `avx512f` and `avx512bw` (`x86-64-v4`). The HT span inserts
///   keep the eight rows of a layer in one 512-bit register (`src/lanes/w512.rs`); the MLAB
///   span inserts, the quantizer and the resolves run on the 256-bit registers of the 8-wide
///   lanes (where 512-bit MLAB lanes measured slower: `docs/performance.md`).
/// - `"avx2 (avx512f build)"`: `avx512f` without `avx512bw` (no `x86-64-v*` level): the
///   8-wide lanes on AVX2, as `wide` compiles them there.
/// - `"avx2"`: one 256-bit register per 8-wide vector.
/// - `"sse2"`: x86 without AVX2, two 128-bit halves (`wide` uses SSSE3, SSE4.1 or AVX where
///   the build has them).
/// - `"neon"`: two 128-bit NEON halves (aarch64).
/// - `"simd128"`: two 128-bit halves (wasm32 with `simd128`).
/// - `"portable"`: no SIMD, plain arrays (wasm32 without `simd128`, any other target).
pub const BACKEND: &str = if cfg!(all(target_feature = "avx512f", target_feature = "avx512bw")) {
    "avx512"
} else if cfg!(target_feature = "avx512f") {
    "avx2 (avx512f build)"
} else if cfg!(target_feature = "avx2") {
    "avx2"
} else if cfg!(target_feature = "sse2") {
    "sse2"
} else if cfg!(all(target_arch = "aarch64", target_feature = "neon")) {
    "neon"
} else if cfg!(all(target_family = "wasm", target_feature = "simd128")) {
    "simd128"
} else {
    "portable"
};

/// Whether the paper's merge packs the first words of the 8 merged rows into one register
/// (as the unbiased merge always does): faster with AVX2, slower on SSE2 at M = 8.
pub(crate) const PACK_PAPER_MERGE: bool = cfg!(target_feature = "avx2");

/// Whether the MLAB rows select with the sign bit of each 64-bit lane (`vblendvpd`, AVX):
/// the depth compare's mask is then used as is; without AVX it is widened from the depth
/// dword to the whole row (`super::w256::Lanes8`).
pub(crate) const SIGN_SELECT: bool = cfg!(target_feature = "avx");
