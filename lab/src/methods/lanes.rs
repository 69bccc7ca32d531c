//! MLAB and HT through the kernel's 8-pixel lanes: the same images as [`super::kernel`], bit
//! for bit.

use super::kernel::{err, image_of};
use super::{Arith, BinnedStream, Image};
use mlab::lanes::LANES;
use mlab::{Arithmetic, Framebuffer, HybridSpanFramebuffer, Paper, Row, SpanBatcher, SpanFramebuffer, Unbiased};

/// A kernel through its 8-pixel lanes: the stream goes, fragment by fragment in submission
/// order, through the kernel's span batcher ([`SpanBatcher`]) into the span framebuffer `fb`
/// (cleared): the batcher gathers the fragments into 8-pixel span inserts, quantized 8 at a
/// time in `fb`'s arithmetic with each fragment's key (its primitive's id,
/// [`crate::stream::Frag::to_kernel`]), and keeps each pixel's submission order exactly.
/// Pixels are independent in MLAB and HT, so the image is the scalar kernel's bit for bit.
/// Resolved a span at a time.
fn run_spans<F: Framebuffer>(binned: &BinnedStream, fb: &mut F) -> Result<Image, String> {
    let s = binned.stream;
    let mut batch = SpanBatcher::new(fb);
    for (i, f) in s.frags.iter().enumerate() {
        let fragment = f.to_kernel().map_err(|e| format!("fragment {i}: {e}"))?;
        batch
            .insert(f.pixel % s.width, f.pixel / s.width, &fragment)
            .map_err(err)?;
    }
    batch.finish().map_err(err)?;
    let mut pixels = Vec::with_capacity(s.pixels());
    for y in 0..s.height {
        for sx in 0..s.width.div_ceil(LANES as u32) {
            let r = fb.resolve_span(sx, y).ok_or("span out of range")?;
            for lane in 0..LANES.min((s.width - sx * LANES as u32) as usize) {
                pixels.push(r.get(lane).ok_or("lane out of range")?);
            }
        }
    }
    image_of(binned, pixels.into_iter().map(Ok))
}

/// MLAB `M` in arithmetic `A` through a [`SpanFramebuffer`].
fn mlab_spans<const M: usize, A: Arithmetic>(binned: &BinnedStream) -> Result<Image, String> {
    let (w, h) = (binned.stream.width, binned.stream.height);
    let mut storage = vec![Row::EMPTY; SpanFramebuffer::<M, A>::rows_needed(w, h).map_err(err)?];
    run_spans(
        binned,
        &mut SpanFramebuffer::<M, A>::new_cleared(&mut storage, w, h).map_err(err)?,
    )
}

/// HT `K` in arithmetic `A` through a [`HybridSpanFramebuffer`].
fn hybrid_spans<const K: usize, A: Arithmetic>(binned: &BinnedStream) -> Result<Image, String> {
    let (w, h) = (binned.stream.width, binned.stream.height);
    let mut storage = vec![Row::EMPTY; HybridSpanFramebuffer::<K, A>::rows_needed(w, h).map_err(err)?];
    run_spans(
        binned,
        &mut HybridSpanFramebuffer::<K, A>::new_cleared(&mut storage, w, h).map_err(err)?,
    )
}

fn mlab_lanes<A: Arithmetic>(m: usize, binned: &BinnedStream) -> Result<Image, String> {
    by_size!(
        m,
        [1, 2, 4, 8],
        mlab_spans::<_, A>(binned),
        Err(format!("MLAB {m} lanes: supported row counts are 1, 2, 4, 8"))
    )
}

fn hybrid_lanes<A: Arithmetic>(k: usize, binned: &BinnedStream) -> Result<Image, String> {
    by_size!(
        k,
        [0, 1, 3, 7],
        hybrid_spans::<_, A>(binned),
        Err(format!("HT {k} lanes: supported head sizes are 0, 1, 3, 7"))
    )
}

/// MLAB `m` (1, 2, 4 or 8) with arithmetic `arith` through the kernel's 8-pixel lanes.
pub fn mlab_lanes_with(m: usize, arith: Arith, binned: &BinnedStream) -> Result<Image, String> {
    match arith {
        Arith::Paper => mlab_lanes::<Paper>(m, binned),
        Arith::Unbiased => mlab_lanes::<Unbiased>(m, binned),
    }
}

/// HT `k` (0, 1, 3 or 7) with arithmetic `arith` through the kernel's 8-pixel lanes.
pub fn hybrid_lanes_with(k: usize, arith: Arith, binned: &BinnedStream) -> Result<Image, String> {
    match arith {
        Arith::Paper => hybrid_lanes::<Paper>(k, binned),
        Arith::Unbiased => hybrid_lanes::<Unbiased>(k, binned),
    }
}
