//! `batch_stream`: the span batcher ([`SpanBatcher`]) against per-pixel inserts into a twin
//! framebuffer of the same type, over every arrangement, both methods, compile-time and
//! run-time sizes; every input runs in both arithmetics.
//!
//! The batcher holds fragments back and inserts them 8 pixels at a time, in an order that
//! differs from the submission order between pixels (never within one). Pixels are
//! independent, so the framebuffer must end up byte-identical to inserting every fragment
//! where it was pushed. The target drives a stream of operations and checks:
//!
//! - every push (fragment or arbitrary row bytes, pixels inside and outside, `u32::MAX`
//!   included) returns what the per-pixel insert returns (`Ok`, or the same
//!   [`FramebufferError`]), and a refused push changes nothing;
//! - `pending()` never exceeds the pushes since the last flush, is 0 after a flush, and is
//!   always 0 where span inserts do not pay ([`Framebuffer::SPAN_INSERTS_PAY`]: the batcher
//!   passes fragments straight through);
//! - after every explicit flush ([`SpanBatcher::framebuffer`]) and at the end
//!   ([`SpanBatcher::finish`]), and after a batcher dropped without finishing, the storage is
//!   byte-identical to the per-pixel twin's.
//!
//! Input: byte 0 picks the framebuffer (see [`batch_stream`]), bytes 1-2 the size (width
//! 1..=160, height 1..=72, so that the batcher's 64 x 32-pixel window wraps around); then
//! operations until the bytes run out.

use crate::input::Input;
use mlab::{
    Arithmetic, DynFramebuffer, Framebuffer, HybridFramebuffer, HybridSpanFramebuffer, Layers, MlabFramebuffer, Paper,
    Row, SpanBatcher, SpanFramebuffer, Unbiased,
};

/// Most operations per input (longer inputs are cut).
const MAX_OPS: usize = 4096;

/// `batch_stream` (see the module docs). Byte 0, modulo 10: `MlabFramebuffer` M = 1, 4;
/// `SpanFramebuffer` M = 1, 4; `HybridFramebuffer` K = 1, 3; `HybridSpanFramebuffer` K = 1,
/// 3; `DynFramebuffer` MLAB or HT with a size from [`Layers::SIZES`] (byte 0 / 10 picks it).
pub fn batch_stream(data: &[u8]) {
    let mut input = Input::new(data);
    let (Some(sel), Some(w), Some(h)) = (input.u8(), input.u8(), input.u8()) else {
        return;
    };
    let (w, h) = (1 + w as u32 % 160, 1 + h as u32 % 72);
    batch_stream_a::<Unbiased>(sel, w, h, input.clone());
    batch_stream_a::<Paper>(sel, w, h, input);
}

/// Two framebuffers of the type `$fb::<$n, A>` over storages of their own, then [`run`].
macro_rules! twins {
    ($fb:ident, $n:literal, $w:expr, $h:expr, $input:expr) => {{
        let rows = $fb::<$n, A>::rows_needed($w, $h).expect("small size");
        let (mut a, mut b) = (vec![Row::EMPTY; rows], vec![Row::EMPTY; rows]);
        run(
            $fb::<$n, A>::new_cleared(&mut a, $w, $h).expect("size"),
            $fb::<$n, A>::new_cleared(&mut b, $w, $h).expect("size"),
            $input,
        )
    }};
}

fn batch_stream_a<A: Arithmetic>(sel: u8, w: u32, h: u32, mut input: Input) {
    match sel % 10 {
        0 => twins!(MlabFramebuffer, 1, w, h, &mut input),
        1 => twins!(MlabFramebuffer, 4, w, h, &mut input),
        2 => twins!(SpanFramebuffer, 1, w, h, &mut input),
        3 => twins!(SpanFramebuffer, 4, w, h, &mut input),
        4 => twins!(HybridFramebuffer, 1, w, h, &mut input),
        5 => twins!(HybridFramebuffer, 3, w, h, &mut input),
        6 => twins!(HybridSpanFramebuffer, 1, w, h, &mut input),
        7 => twins!(HybridSpanFramebuffer, 3, w, h, &mut input),
        m => {
            let size = Layers::SIZES[(sel / 10) as usize % Layers::SIZES.len()];
            let layers = if m == 8 {
                Layers::Mlab(size)
            } else {
                Layers::Hybrid(size)
            };
            let rows = layers.rows_needed(w, h).expect("small size");
            let (mut a, mut b) = (vec![Row::EMPTY; rows], vec![Row::EMPTY; rows]);
            run(
                DynFramebuffer::<A>::new_cleared(layers, &mut a, w, h).expect("size"),
                DynFramebuffer::<A>::new_cleared(layers, &mut b, w, h).expect("size"),
                &mut input,
            )
        }
    }
}

/// A pixel: mostly inside, some just outside, a few far outside.
fn pixel(input: &mut Input, w: u32, h: u32) -> Option<(u32, u32)> {
    let (x, y) = (input.u16()?, input.u8()?);
    Some(match x >> 13 {
        7 if x & 1 == 0 => (u32::MAX, y as u32 % (h + 2)),
        7 => (x as u32 % (w + 2), u32::MAX - y as u32),
        _ => (x as u32 % (w + 2), y as u32 % (h + 2)),
    })
}

/// Drive `batched` through a [`SpanBatcher`] and `reference` pixel by pixel with the same
/// operations; see the module docs for what is checked.
fn run<F: Framebuffer>(mut reference: F, mut batched: F, input: &mut Input) {
    let (w, h) = (reference.width(), reference.height());
    // Pushes since the last flush that were accepted.
    let mut since_flush = 0usize;
    let mut batch = SpanBatcher::new(&mut batched);
    for _ in 0..MAX_OPS {
        let Some(op) = input.u8() else { break };
        match op % 16 {
            // Fragments (any constructor; refused ones are the fragment targets' business).
            0..=10 => {
                let (Some((x, y)), Some(raw)) = (pixel(input, w, h), input.raw_fragment()) else {
                    break;
                };
                let Ok(f) = raw.build() else { continue };
                let want = reference.insert(x, y, &f);
                assert_eq!(batch.insert(x, y, &f), want, "fragment at ({x}, {y}) in {w} x {h}");
                since_flush += usize::from(want.is_ok());
            }
            // Arbitrary bytes as a row (NaN depths, any color and transmittance).
            11..=13 => {
                let (Some((x, y)), Some(bytes)) = (pixel(input, w, h), input.array::<8>()) else {
                    break;
                };
                let row = Row::from_bytes(bytes);
                let want = reference.insert_row(x, y, row);
                assert_eq!(batch.insert_row(x, y, row), want, "row at ({x}, {y}) in {w} x {h}");
                since_flush += usize::from(want.is_ok());
            }
            // Flush and compare, then go on batching.
            14 => {
                let fb = batch.framebuffer().expect("a flush cannot fail");
                assert_eq!(fb.as_bytes(), reference.as_bytes(), "after a flush");
                since_flush = 0;
                assert_eq!(batch.pending(), 0);
            }
            // Drop the batcher unfinished (drop flushes), compare, start a new one.
            _ => {
                drop(batch);
                assert_eq!(batched.as_bytes(), reference.as_bytes(), "after a drop");
                since_flush = 0;
                batch = SpanBatcher::new(&mut batched);
            }
        }
        let pending = batch.pending();
        assert!(pending <= since_flush, "{pending} pending of {since_flush} pushes");
        if !F::SPAN_INSERTS_PAY {
            assert_eq!(pending, 0, "pending where span inserts do not pay");
        }
    }
    batch.finish().expect("a flush cannot fail");
    assert_eq!(batched.as_bytes(), reference.as_bytes(), "at the end");
}
