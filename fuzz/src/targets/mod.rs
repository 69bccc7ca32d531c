//! Four of the fuzz targets, one a file (the fifth, `batch_stream`, is in [`crate::batch`]):
//! [`mlab_stream`], [`hybrid_stream`], [`rows_from_bytes`], [`lanes_masks`]. Each takes the
//! raw fuzzer bytes; the first byte chooses the const parameters (rows per pixel), the rest
//! is decoded by [`Input`]. Every target runs each input twice, once in each arithmetic of
//! the kernel ([`Paper`](mlab::Paper), the paper's rounding and tail, and [`Unbiased`], the
//! default: dithered rounding and the wide tail), against the reference model of that
//! arithmetic ([`Model`](mlab_reference::Model)).
//!
//! This file holds what the targets share: the fragment parts the oracle takes, the lane
//! masks and rows of the lanes differentials, the integer resolve check of MLAB rows. The
//! targets import it; it imports none of them.

use mlab::framebuffer::Arrangement;
use mlab::glam::Vec3;
use mlab::lanes::LANES;
use mlab::{Arithmetic, Background, BlendingArray, Fragment, Framebuffer, Grid, PixelMajor, Row, Spans, Unbiased};
use mlab_reference::oracle::oracle;

use crate::input::Input;

pub mod hybrid_stream;
pub mod lanes_masks;
pub mod mlab_stream;
pub mod rows_from_bytes;

/// An MLAB span, layer-major (`span[j][lane]`).
pub(crate) type MlabSpan<const M: usize> = [[Row; LANES]; M];

/// The kernel's default arithmetic is [`Unbiased`]: `BlendingArray<M>` is
/// `BlendingArray<M, Unbiased>` (a compile error here if the default changes).
const _: fn(BlendingArray<1>) -> BlendingArray<1, Unbiased> = |a| a;

/// True for the default arithmetic, whose entry points without a type parameter
/// (`mlab::merge`, `lanes::mlab_insert`, `FragmentLanes::quantize`, ...) the targets
/// check too.
pub(crate) fn is_default<A: Arithmetic>() -> bool {
    A::NAME == Unbiased::NAME
}

/// Most fragments per stream (longer inputs are cut).
pub const MAX_FRAGMENTS: usize = 64;

/// The limit the targets check for a resolved tail's color (see
/// [`mlab_reference::kind::tail_color_limit`]). Finding F1, the tail amplifying its light
/// above it, was fixed in d37150f: the color factor `g = (1 - T_tail) / S_a` is evaluated as
/// `S_n / n` and clamped to at most 1 (`S_n <= n` but for rounding), and where the mean
/// alpha exceeds 1 (arbitrary bytes) the mean is clamped to 1 and `g = 1 / S_a < 1`
/// (`resolve::tail_lanes`).
pub use mlab_reference::kind::tail_color_limit;

/// Run a target's body on the input after byte 0 (`sel`, which picks the const parameters)
/// once in each arithmetic, the paper's first, each from the same bytes.
pub(crate) fn in_both_arithmetics<'a>(data: &'a [u8], paper: fn(u8, Input<'a>), unbiased: fn(u8, Input<'a>)) {
    let mut input = Input::new(data);
    let Some(sel) = input.u8() else { return };
    paper(sel, input.clone());
    unbiased(sel, input);
}

/// A fragment's parts as the oracle takes them.
pub(crate) type Parts = ([f32; 3], f32, f32);

/// `(premultiplied color, alpha, depth)` of an accepted fragment, for the oracle.
pub(crate) fn parts(f: &Fragment) -> Parts {
    (f.color().to_array(), f.alpha(), f.depth())
}

/// Premultiplied color not above alpha: the condition of the oracle bound.
pub(crate) fn occluding(frags: &[Parts]) -> bool {
    frags.iter().all(|(c, a, _)| c.iter().all(|v| v <= a))
}

/// The f64 oracle over a black background (the transparent layers alone), as
/// [`check_close`](crate::check::check_close) compares it with a resolved pixel.
pub(crate) fn exact(frags: &[Parts]) -> ([f64; 3], f64) {
    oracle(frags, [0.0; 3])
}

/// A lanes check of `mlab_reference::lanes`: a failure is a crash.
pub(crate) fn lanes_ok(r: Result<(), String>) {
    if let Err(e) = r {
        panic!("lanes differ from scalar: {e}");
    }
}

// ---------------------------------------------------------------------------------------
// Lanes differentials (lanes == scalar, byte for byte and bit for bit)

/// A mask for the n-th fragment of a stream: lane 0 always on, the others scattered.
pub fn lane_mask(n: usize) -> u8 {
    1 | ((n as u32 + 1).wrapping_mul(0x9e37_79b9) >> 24) as u8
}

/// A garbage row handed to lanes that are off (a NaN depth and full color): it must never
/// reach a pixel.
pub const OFF_LANE_ROW: Row = Row::from_bytes([0xab, 0xcd, 0xef, 0x01, 0xff, 0xff, 0xff, 0xff]);

/// `row` in the lanes that are on, [`OFF_LANE_ROW`] in the others.
pub fn lane_rows(row: Row, mask: u8) -> [Row; LANES] {
    core::array::from_fn(|lane| if mask >> lane & 1 == 1 { row } else { OFF_LANE_ROW })
}

/// The span in the per-pixel arrangement, `[pixel][row]` (a transpose).
pub(crate) fn to_pixel_major<const M: usize>(span: &MlabSpan<M>) -> [[Row; M]; LANES] {
    core::array::from_fn(|lane| core::array::from_fn(|j| span[j][lane]))
}

/// The inverse of [`to_pixel_major`].
pub(crate) fn from_pixel_major<const M: usize>(pixels: &[[Row; M]; LANES]) -> MlabSpan<M> {
    core::array::from_fn(|j| core::array::from_fn(|lane| pixels[lane][j]))
}

// ---------------------------------------------------------------------------------------
// Integer resolve

/// The backgrounds of the integer resolve checks: transparent, black, white and a color.
pub(crate) const INT_BACKGROUNDS: [Background; 4] = [
    Background::Transparent,
    Background::Opaque(Vec3::ZERO),
    Background::Opaque(Vec3::ONE),
    Background::Opaque(Vec3::new(0.2, 0.5, 0.7)),
];

/// An integer resolve `got` within `bound` of the exact composite, channel by channel (the
/// bounds of `mlab_reference::resolve_int`); `what` names the resolve in the message (called
/// only on a failure).
pub(crate) fn check_int_bound(got: [u8; 4], exact: [f64; 4], bound: [f64; 4], what: impl Fn() -> String) {
    for ch in 0..4 {
        let err = (f64::from(got[ch]) - exact[ch]).abs();
        assert!(
            err <= bound[ch] + 1e-9,
            "{}: channel {ch} {} vs exact {} (bound {})",
            what(),
            got[ch],
            exact[ch],
            bound[ch]
        );
    }
}

/// The RGBA8 resolve of an 8 x 1 MLAB framebuffer of the arrangement `L` over `storage`.
fn span_rgba8<const M: usize, L: Arrangement>(mut storage: Vec<Row>, bg: Background) -> [[u8; 4]; LANES] {
    let mut out = [[0u8; 4]; LANES];
    Grid::<mlab::Mlab<M>, L>::new(&mut storage, 8, 1)
        .expect("8 x 1")
        .resolve_rgba8(&mut out, bg)
        .expect("8 x 1");
    out
}

/// The integer RGBA8 resolve of MLAB rows (`SpanFramebuffer::resolve_rgba8` and
/// `MlabFramebuffer::resolve_rgba8` of one 8-pixel span holding them in every lane) against
/// the reference formula byte for byte, and the reference against the exact composite of
/// the rows within the derived bound (`mlab_reference::resolve_int`), over
/// [`INT_BACKGROUNDS`].
pub(crate) fn check_int_resolve<const M: usize>(rows: &[Row; M], context: &dyn core::fmt::Debug) {
    for bg in INT_BACKGROUNDS {
        let want = mlab_reference::resolve_int::rgba8(rows, bg);
        let pm: Vec<Row> = (0..LANES).flat_map(|_| rows.iter().copied()).collect();
        assert_eq!(
            span_rgba8::<M, PixelMajor>(pm, bg),
            [want; LANES],
            "M = {M} pixel-major integer resolve {bg:?} of {rows:?} ({context:?})"
        );
        let sp: Vec<Row> = rows.iter().flat_map(|&r| [r; LANES]).collect();
        assert_eq!(
            span_rgba8::<M, Spans>(sp, bg),
            [want; LANES],
            "M = {M} span integer resolve {bg:?} of {rows:?} ({context:?})"
        );
        let exact = mlab_reference::resolve_int::exact(rows, bg);
        let bound = mlab_reference::resolve_int::bound(rows, bg);
        check_int_bound(want, exact, bound, || {
            format!("M = {M} integer resolve {bg:?} of {rows:?} ({context:?})")
        });
    }
}
