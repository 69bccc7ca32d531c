//! The resolves: every pixel composited over a background into the caller's RGBA8, f32 or
//! RGBA16F image.

use mlab::framebuffer::Output;
use mlab::glam::{Vec3, Vec4};
use mlab::half::f16;
use mlab::{Background, Framebuffer};

use crate::boundary::{check_ptr, guard};
use crate::framebuffer::{MlabFramebuffer, state, with_grid};
use crate::status::MlabStatus;
use crate::types::{MLAB_BACKGROUND_OPAQUE, MLAB_BACKGROUND_TRANSPARENT, MlabBackground};

/// An output slice of `pixels` elements of `T` at `out`, after checking the pointer
/// (alignment `align`) and that it holds exactly `width * height` pixels.
///
/// # Safety
/// `out`, if non-null, is valid for writes of `pixels` elements of `T` for `'o`, and used by
/// nothing else meanwhile; any bit pattern is a valid `T`.
#[inline(always)]
unsafe fn output<'o, T>(
    s: &MlabFramebuffer,
    out: *mut T,
    pixels: usize,
    align: usize,
) -> Result<&'o mut [T], MlabStatus> {
    check_ptr(out, align)?;
    if pixels as u64 != s.width as u64 * s.height as u64 {
        return Err(MlabStatus::OutputLength);
    }
    if pixels > isize::MAX as usize / size_of::<T>() {
        return Err(MlabStatus::SizeOverflow);
    }
    // SAFETY: non-null, aligned (checked), at most isize::MAX bytes (checked); valid and
    // exclusive for `pixels` elements by the caller's guarantee; any bits are a valid `T`.
    Ok(unsafe { core::slice::from_raw_parts_mut(out, pixels) })
}

/// The kernel's background.
fn background(bg: MlabBackground) -> Result<Background, MlabStatus> {
    match bg.kind {
        MLAB_BACKGROUND_TRANSPARENT => Ok(Background::Transparent),
        MLAB_BACKGROUND_OPAQUE => Ok(Background::Opaque(Vec3::from_array(bg.rgb))),
        _ => Err(MlabStatus::InvalidArgument),
    }
}

/// Every pixel resolved into `out`, `out_pixels` pixels of the format `O` aligned to `align`
/// bytes: the body of the three resolves.
///
/// # Safety
/// As `mlab_resolve_rgba8`, `out` valid for writes of `out_pixels` `O`; any bits are a valid `O`.
unsafe fn resolve<O: Output>(
    fb: *const MlabFramebuffer,
    background: MlabBackground,
    out: *mut O,
    out_pixels: usize,
    align: usize,
) -> MlabStatus {
    guard(|| {
        // SAFETY: the caller's guarantee on `fb`.
        let s = unsafe { state(fb) }?;
        let bg = self::background(background)?;
        // SAFETY: the caller's guarantee on `out`.
        let out = unsafe { output(s, out, out_pixels, align) }?;
        with_grid!(s, f => Ok(f.resolve_as(out, bg)?))
    })
}

/// Resolves every pixel into RGBA8 (`out`: `4 * out_pixels` bytes, `out_pixels = width *
/// height`, row-major, R, G, B, A per pixel): the kernel's integer resolve (the same bytes in
/// scalar code, every SIMD backend and its WGSL twin), linear unorm8 (not sRGB), over
/// `background` (opaque: alpha 255; transparent: premultiplied).
///
/// # Safety
/// `fb` as for `mlab_insert_straight` (the rows are read); `out` is null or valid for
/// writes of `4 * out_pixels` bytes.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn mlab_resolve_rgba8(
    fb: *const MlabFramebuffer,
    background: MlabBackground,
    out: *mut u8,
    out_pixels: usize,
) -> MlabStatus {
    // SAFETY: the caller's guarantee, passed on; `[u8; 4]` takes any bits.
    unsafe { resolve(fb, background, out.cast::<[u8; 4]>(), out_pixels, 1) }
}

/// Resolves every pixel into f32 RGBA (`out`: `4 * out_pixels` floats, **16-byte aligned**,
/// row-major): the kernel's f32 resolve (Eq. 5 and 6), linear, over `background`.
///
/// # Safety
/// As `mlab_resolve_rgba8`, `out` valid for writes of `4 * out_pixels` floats.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn mlab_resolve_f32(
    fb: *const MlabFramebuffer,
    background: MlabBackground,
    out: *mut f32,
    out_pixels: usize,
) -> MlabStatus {
    const { assert!(size_of::<Vec4>() == 16 && align_of::<Vec4>() <= 16) };
    // SAFETY: the caller's guarantee, passed on; a `Vec4` is four f32 (asserted above: 16
    // bytes, alignment at most the 16 checked), any bits valid.
    unsafe { resolve(fb, background, out.cast::<Vec4>(), out_pixels, 16) }
}

/// Resolves every pixel into RGBA16F (`out`: `4 * out_pixels` IEEE binary16 values as
/// `uint16_t`, 2-byte aligned, row-major): the f32 resolve rounded to nearest half, linear.
///
/// # Safety
/// As `mlab_resolve_rgba8`, `out` valid for writes of `4 * out_pixels` `uint16_t`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn mlab_resolve_rgba16f(
    fb: *const MlabFramebuffer,
    background: MlabBackground,
    out: *mut u16,
    out_pixels: usize,
) -> MlabStatus {
    const { assert!(size_of::<[f16; 4]>() == 8 && align_of::<[f16; 4]>() == 2) };
    // SAFETY: the caller's guarantee, passed on; `f16` is a transparent u16 (any bits).
    unsafe { resolve(fb, background, out.cast::<[f16; 4]>(), out_pixels, 2) }
}
