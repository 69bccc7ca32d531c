//! The writers of a whole-frame resolve into a row-major output of `width * height` pixels:
//! whole spans first, as arrays, then the partial last span of each line ([`write_edge`]).

// Span and line indices are below the u32 width and height.
#![expect(
    clippy::cast_possible_truncation,
    reason = "span and line indices fit the u32 width and height"
)]

use super::dims::Dims;
use crate::error::FramebufferError;
use crate::lanes::LANES;
use crate::row::Row;

/// Write the 8 lanes of each span (`span(span_index_in_line, y)`) into a row-major output
/// of `width * height` pixels, dropping lanes past the right edge. Whole spans are written as
/// arrays, a fixed-size store each (a copy of `o.len()` elements, the same for every chunk,
/// compiled to a call to `memmove` per span: 16-22 % of an RGBA8 resolve at M = 1).
pub(crate) fn write_spans<T: Copy>(
    d: Dims,
    out: &mut [T],
    span: impl Fn(u32, u32) -> [T; LANES],
) -> Result<(), FramebufferError> {
    for (y, line) in out_lines(d, out)?.enumerate() {
        let (whole, rest) = line.as_chunks_mut::<LANES>();
        for (sx, o) in whole.iter_mut().enumerate() {
            *o = span(sx as u32, y as u32);
        }
        if !rest.is_empty() {
            write_edge(rest, &span, whole.len() as u32, y as u32);
        }
    }
    Ok(())
}

/// [`write_spans`] with the whole spans of each line written by `whole` from the line's
/// `line_rows` rows of `rows` (a framebuffer's own loop, without index maths or a bounds
/// check per span). Two writers, not one taking a closure per line: written as one, the
/// resolves ran 2 to 10 % more instructions (callgrind, `docs/performance.md`).
pub(crate) fn write_lines<T: Copy>(
    d: Dims,
    out: &mut [T],
    rows: &[Row],
    line_rows: usize,
    whole: impl Fn(&[Row], &mut [[T; LANES]]),
    edge: impl Fn(u32, u32) -> [T; LANES],
) -> Result<(), FramebufferError> {
    for (y, (line, src)) in out_lines(d, out)?.zip(rows.chunks_exact(line_rows.max(1))).enumerate() {
        let (spans, rest) = line.as_chunks_mut::<LANES>();
        whole(src, spans);
        if !rest.is_empty() {
            write_edge(rest, &edge, spans.len() as u32, y as u32);
        }
    }
    Ok(())
}

/// The lines of a row-major output of `width * height` pixels, after checking its length
/// (none where the width is 0).
fn out_lines<T>(d: Dims, out: &mut [T]) -> Result<core::slice::ChunksExactMut<'_, T>, FramebufferError> {
    d.check_output(out.len())?;
    Ok(out.chunks_exact_mut((d.width as usize).max(1)))
}

/// The partial last span of a line (`rest`: its 1 to 7 pixels inside), by `edge(span, y)`:
/// a call of its own, once per line where the width is not a multiple of 8, so that the
/// loops over whole spans hold only their code.
#[inline(never)]
fn write_edge<T: Copy>(rest: &mut [T], edge: &impl Fn(u32, u32) -> [T; LANES], span: u32, y: u32) {
    let px = edge(span, y);
    rest.copy_from_slice(px.get(..rest.len()).unwrap_or(&px));
}
