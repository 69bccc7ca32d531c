//! The CPU kernel on the compositor's input: the oracle the GPU path is compared with, and a
//! fallback that gives the same bytes. Written over the kernel's public API alone (the
//! compositor does not use this module).

use crate::error::GpuError;
use crate::fragment::GpuFragment;
use crate::plan::{Layout, validate};
use mlab::{
    ArithKind, Arithmetic, Background, DynFramebuffer, Framebuffer, FramebufferError, Layers, Paper, Row, Unbiased,
};

fn framebuffer_error(layers: Layers, width: u32, height: u32, e: FramebufferError) -> GpuError {
    match e {
        FramebufferError::UnsupportedLayers { .. } => GpuError::UnsupportedLayers(layers),
        _ => GpuError::FrameTooLarge { width, height },
    }
}

/// The storage words of a `width x height` framebuffer of `layers` in the arithmetic `arith`,
/// cleared, after inserting `fragments` in order with [`Framebuffer::insert`] on the kernel's
/// [`DynFramebuffer`] (spans; each fragment with its stable key when it has one, so its hash is
/// [`mlab::Fragment::hash`] of its `pixel`); for [`Layout::PixelMajor`] its pixels in that order
/// ([`DynFramebuffer::copy_to_pixel_major`], `docs/layout.md`). Errors as
/// [`crate::Compositor::composite`].
pub fn composite(
    layers: Layers,
    arith: ArithKind,
    layout: Layout,
    width: u32,
    height: u32,
    fragments: &[GpuFragment],
) -> Result<Vec<u32>, GpuError> {
    match arith {
        ArithKind::Paper => composite_in::<Paper>(layers, layout, width, height, fragments),
        ArithKind::Unbiased => composite_in::<Unbiased>(layers, layout, width, height, fragments),
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
    Ok(match layout {
        Layout::Spans => fb.as_words().to_vec(),
        Layout::PixelMajor => {
            let mut rows = vec![Row::EMPTY; pixels as usize * layers.rows_per_pixel()];
            fb.copy_to_pixel_major(&mut rows).map_err(err)?;
            rows.iter().flat_map(|r| r.words()).collect()
        }
    })
}

/// The kernel's `Framebuffer::resolve_rgba8` of the framebuffer [`composite`] builds (the
/// integer resolve for MLAB): `width * height` pixels, row-major.
pub fn resolve_rgba8(
    layers: Layers,
    arith: ArithKind,
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
        ArithKind::Paper => DynFramebuffer::<Paper>::new(layers, &mut rows, width, height)
            .and_then(|fb| fb.resolve_rgba8(&mut out, background))
            .map_err(err)?,
        ArithKind::Unbiased => DynFramebuffer::<Unbiased>::new(layers, &mut rows, width, height)
            .and_then(|fb| fb.resolve_rgba8(&mut out, background))
            .map_err(err)?,
    }
    Ok(out)
}
