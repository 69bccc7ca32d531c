//! The batch inserts: an array of fragments, each with its pixel (`MlabPixelFragment`, or
//! `MlabPixelFragmentKeyed` with a key), through the kernel's span batcher. One generic body
//! (`insert_batch`) serves the four exported functions.

use mlab::{Framebuffer, SpanBatcher};

use crate::boundary::{check_ptr, guard};
use crate::fragment::{MlabPixelFragment, MlabPixelFragmentKeyed, PixelFragment, fragment};
use crate::framebuffer::{MlabFramebuffer, state, with_grid};
use crate::status::MlabStatus;

/// `events` through a span batcher over `fb`, stopping at the first refused one: how many
/// went in, and the status. A function of its own (not inlined into each arm of
/// `with_grid!`), so that one batcher (about 52 KiB) is on the stack, not one per arm.
#[inline(never)]
fn batch_into<F: Framebuffer, E: PixelFragment>(
    fb: &mut F,
    events: &[E],
    straight: bool,
) -> Result<(usize, Result<(), MlabStatus>), MlabStatus> {
    let (width, height) = (fb.width(), fb.height());
    let mut batch = SpanBatcher::new(fb);
    for (i, e) in events.iter().enumerate() {
        let (x, y, rgba, depth, key) = e.parts();
        // The pixel, then the fragment (`docs/c.md`, "The order of the checks").
        let r = if x >= width || y >= height {
            Err(MlabStatus::OutOfBounds)
        } else {
            fragment(rgba, depth, key, straight)
                .map_err(MlabStatus::from)
                .and_then(|v| Ok(batch.insert(x, y, &v)?))
        };
        if let Err(st) = r {
            batch.finish()?;
            return Ok((i, Err(st)));
        }
    }
    batch.finish()?;
    Ok((events.len(), Ok(())))
}

/// A batch of fragments (keyed or not) through the kernel's span batcher.
///
/// # Safety
/// As `mlab_insert_batch_straight`, `fragments` null or valid for reads of `count` `E`.
unsafe fn insert_batch<E: PixelFragment>(
    fb: *mut MlabFramebuffer,
    fragments: *const E,
    count: usize,
    inserted: *mut usize,
    straight: bool,
) -> MlabStatus {
    guard(|| {
        // SAFETY: the caller's guarantee on `fb`.
        let s = unsafe { state(fb) }?;
        check_ptr(inserted, align_of::<usize>())?;
        if count == 0 {
            // Nothing to insert: no fragment read (`fragments` may be null: an empty array).
            // SAFETY: non-null and aligned (checked), writable (the caller's guarantee).
            unsafe { inserted.write(0) };
            return Ok(());
        }
        check_ptr(fragments, align_of::<E>())?;
        if count > isize::MAX as usize / size_of::<E>() {
            return Err(MlabStatus::SizeOverflow);
        }
        // SAFETY: non-null, aligned, at most isize::MAX bytes (checked); readable for
        // `count` fragments and not written during the call (the caller's guarantee).
        let events = unsafe { core::slice::from_raw_parts(fragments, count) };
        let (done, status) = with_grid!(s, f => batch_into(&mut f, events, straight))?;
        // SAFETY: non-null and aligned (checked), writable (the caller's guarantee).
        unsafe { inserted.write(done) };
        status
    })
}

/// Inserts `count` fragments (straight color) in array order, each into its own pixel,
/// through the kernel's span batcher (fragments gathered into 8-pixel span inserts inside
/// the call): byte-identical to calling `mlab_insert_straight` on each in order, faster
/// for MLAB when the fragments of a line come together (`docs/performance.md`). Stops at
/// the first fragment that is outside or invalid (its pixel checked first, then its values):
/// `*inserted` is then its index (the fragments before it are in the framebuffer, it and
/// those after it are not) and the status says why; otherwise `*inserted = count`. Count 0
/// inserts nothing: `MLAB_STATUS_OK`, `*inserted = 0`, `fragments` not read (may be null, as
/// an empty array's is). Uses about 52 KiB of stack.
///
/// # Safety
/// `fb` as for `mlab_insert_straight`; `fragments` is null or valid for reads of `count`
/// fragments; `inserted` is null or valid for a write of one `size_t`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn mlab_insert_batch_straight(
    fb: *mut MlabFramebuffer,
    fragments: *const MlabPixelFragment,
    count: usize,
    inserted: *mut usize,
) -> MlabStatus {
    // SAFETY: the caller's guarantee, passed on.
    unsafe { insert_batch(fb, fragments, count, inserted, true) }
}

/// `mlab_insert_batch_straight` with premultiplied color.
///
/// # Safety
/// As `mlab_insert_batch_straight`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn mlab_insert_batch_premultiplied(
    fb: *mut MlabFramebuffer,
    fragments: *const MlabPixelFragment,
    count: usize,
    inserted: *mut usize,
) -> MlabStatus {
    // SAFETY: the caller's guarantee, passed on.
    unsafe { insert_batch(fb, fragments, count, inserted, false) }
}

/// `mlab_insert_batch_straight` of fragments with stable keys (`MlabPixelFragmentKeyed`,
/// the key as in `mlab_insert_straight_keyed`): byte-identical to calling
/// `mlab_insert_straight_keyed` on each in order. The same checks, statuses and `*inserted`.
///
/// # Safety
/// As `mlab_insert_batch_straight`, `fragments` null or valid for reads of `count`
/// `MlabPixelFragmentKeyed`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn mlab_insert_batch_straight_keyed(
    fb: *mut MlabFramebuffer,
    fragments: *const MlabPixelFragmentKeyed,
    count: usize,
    inserted: *mut usize,
) -> MlabStatus {
    // SAFETY: the caller's guarantee, passed on.
    unsafe { insert_batch(fb, fragments, count, inserted, true) }
}

/// `mlab_insert_batch_straight_keyed` with premultiplied color.
///
/// # Safety
/// As `mlab_insert_batch_straight_keyed`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn mlab_insert_batch_premultiplied_keyed(
    fb: *mut MlabFramebuffer,
    fragments: *const MlabPixelFragmentKeyed,
    count: usize,
    inserted: *mut usize,
) -> MlabStatus {
    // SAFETY: the caller's guarantee, passed on.
    unsafe { insert_batch(fb, fragments, count, inserted, false) }
}
