//! The CPU kernel on the compositor's input: the oracle the GPU path is compared with, and a
//! fallback that gives the same bytes.

use crate::{Arith, GpuError, GpuFragment, Layout};
use mlab::{
    Arithmetic, Background, DynFramebuffer, Fragment, Framebuffer, FramebufferError, Layers, Paper, Row, Unbiased,
};

/// Validates a fragment as the compositor does; the [`Fragment`] carries its stable key, if
/// it has one.
pub(crate) fn validate(index: usize, f: &GpuFragment, pixels: u32) -> Result<Fragment, GpuError> {
    if f.pixel >= pixels {
        return Err(GpuError::PixelOutOfRange {
            index,
            pixel: f.pixel,
            pixels,
        });
    }
    let fragment =
        Fragment::premultiplied_rgba(f.rgba, f.depth).map_err(|error| GpuError::Fragment { index, error })?;
    Ok(match f.key() {
        Some(key) => fragment.with_key(key),
        None => fragment,
    })
}

fn framebuffer_error(layers: Layers, width: u32, height: u32, e: FramebufferError) -> GpuError {
    match e {
        FramebufferError::UnsupportedLayers { .. } => GpuError::UnsupportedLayers(layers),
        _ => GpuError::FrameTooLarge { width, height },
    }
}

/// The storage words of a `width x height` framebuffer of `layers` in the arithmetic `arith`,
/// cleared, after inserting `fragments` in order with [`Framebuffer::insert`] on the kernel's
/// [`DynFramebuffer`] (spans; each fragment with its stable key when it has one, so its hash is
/// [`mlab::Fragment::hash`] of its `pixel`); for [`Layout::PixelMajor`] its slots re-indexed pixel by pixel
/// (`docs/layout.md`). Errors as [`crate::Compositor::composite`].
pub fn composite(
    layers: Layers,
    arith: Arith,
    layout: Layout,
    width: u32,
    height: u32,
    fragments: &[GpuFragment],
) -> Result<Vec<u32>, GpuError> {
    match arith {
        Arith::Paper => composite_in::<Paper>(layers, layout, width, height, fragments),
        Arith::Unbiased => composite_in::<Unbiased>(layers, layout, width, height, fragments),
    }
}

fn composite_in<A: Arithmetic>(
    layers: Layers,
    layout: Layout,
    width: u32,
    height: u32,
    fragments: &[GpuFragment],
) -> Result<Vec<u32>, GpuError> {
    let err = |e| framebuffer_error(layers, width, height, e);
    let pixels = width
        .checked_mul(height)
        .ok_or(GpuError::FrameTooLarge { width, height })?;
    let mut storage = vec![Row::EMPTY; layers.rows_needed(width, height).map_err(err)?];
    let mut fb = DynFramebuffer::<A>::new_cleared(layers, &mut storage, width, height).map_err(err)?;
    for (index, f) in fragments.iter().enumerate() {
        let fragment = validate(index, f, pixels)?;
        fb.insert(f.pixel % width, f.pixel / width, &fragment).map_err(err)?;
    }
    let spans = fb.as_words().to_vec();
    Ok(match layout {
        Layout::Spans => spans,
        Layout::PixelMajor => {
            let slots = slots(layers);
            let stride = (width as usize).div_ceil(8);
            let mut out = Vec::with_capacity(pixels as usize * slots * 2);
            for y in 0..height as usize {
                for x in 0..width as usize {
                    for j in 0..slots {
                        let i = ((y * stride + x / 8) * slots + j) * 8 + x % 8;
                        out.extend_from_slice(&spans[2 * i..2 * i + 2]);
                    }
                }
            }
            out
        }
    })
}

/// 8-byte slots per pixel: `M`, or `K + 1` (the tail).
pub(crate) const fn slots(layers: Layers) -> usize {
    match layers {
        Layers::Mlab(m) => m,
        Layers::Hybrid(k) => k + 1,
    }
}

/// The kernel's `Framebuffer::resolve_rgba8` of the framebuffer [`composite`] builds (the
/// integer resolve for MLAB): `width * height` pixels, row-major.
pub fn resolve_rgba8(
    layers: Layers,
    arith: Arith,
    width: u32,
    height: u32,
    fragments: &[GpuFragment],
    background: Background,
) -> Result<Vec<[u8; 4]>, GpuError> {
    let err = |e| framebuffer_error(layers, width, height, e);
    let words = composite(layers, arith, Layout::Spans, width, height, fragments)?;
    let mut rows: Vec<Row> = words.chunks_exact(2).map(|w| Row::from_words([w[0], w[1]])).collect();
    let mut out = vec![[0u8; 4]; (width as usize) * (height as usize)];
    match arith {
        Arith::Paper => DynFramebuffer::<Paper>::new(layers, &mut rows, width, height)
            .and_then(|fb| fb.resolve_rgba8(&mut out, background))
            .map_err(err)?,
        Arith::Unbiased => DynFramebuffer::<Unbiased>::new(layers, &mut rows, width, height)
            .and_then(|fb| fb.resolve_rgba8(&mut out, background))
            .map_err(err)?,
    }
    Ok(out)
}
