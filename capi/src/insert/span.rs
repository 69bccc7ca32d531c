//! The span inserts: 8 fragments of one line (`MlabFragmentSpan`, or `MlabFragmentSpanKeyed`
//! with a key per lane) in one call, straight or premultiplied color. One generic body
//! (`insert_span`) serves the four exported functions.

use mlab::Framebuffer;

use crate::boundary::{check_ptr, guard};
use crate::fragment::{MlabFragmentSpan, MlabFragmentSpanKeyed, SpanFragments, fragment};
use crate::framebuffer::{MlabFramebuffer, state, with_grid};
use crate::status::MlabStatus;

/// A span insert of fragments (straight color or not, keyed or not).
///
/// # Safety
/// As `mlab_insert_span_straight`, `fragments` null or valid for a read of one `T`.
unsafe fn insert_span<T: SpanFragments>(
    fb: *mut MlabFramebuffer,
    x: u32,
    y: u32,
    fragments: *const T,
    mask: u8,
    refused: *mut u8,
    straight: bool,
) -> MlabStatus {
    guard(|| {
        // SAFETY: the caller's guarantee on `fb`.
        let s = unsafe { state(fb) }?;
        check_ptr(refused, 1)?;
        if mask == 0 {
            // Nothing to insert: no fragment read, no coordinate checked (`docs/c.md`).
            // SAFETY: non-null (checked), writable (the caller's guarantee).
            unsafe { refused.write(0) };
            return Ok(());
        }
        check_ptr(fragments, align_of::<T>())?;
        // SAFETY: non-null, aligned (checked), readable (the caller's guarantee); a copy.
        let lanes = unsafe { fragments.read() }.lanes();
        let invalid = with_grid!(s, f => {
            let r = if straight {
                f.insert_span_straight(x, y, &lanes, mask)
            } else {
                f.insert_span_fragments(x, y, &lanes, mask)
            };
            r.map_err(MlabStatus::from)
        })?;
        // SAFETY: non-null (checked), writable (the caller's guarantee).
        unsafe { refused.write(invalid.0) };
        if invalid.0 == 0 {
            return Ok(());
        }
        // The first refused lane's reason, by the scalar constructor (the same checks).
        let i = invalid.0.trailing_zeros() as usize;
        let rgba = [lanes.color[0][i], lanes.color[1][i], lanes.color[2][i], lanes.alpha[i]];
        match fragment(rgba, lanes.depth[i], None, straight) {
            Err(e) => Err(e.into()),
            Ok(_) => Err(MlabStatus::Internal),
        }
    })
}

/// Inserts the lanes of `*fragments` that are on in `mask` (bit `i`: pixel `(x + i, y)`),
/// straight color, 8 at a time: byte-identical to `mlab_insert_straight` lane by lane, in
/// lane order. `x` need not be a multiple of 8; every lane that is on must lie inside,
/// checked before any fragment (otherwise `MLAB_STATUS_OUT_OF_BOUNDS` and nothing changes).
/// `*refused` gets the mask of the lanes that were on and held an invalid fragment: these
/// are skipped, the valid lanes are inserted, and the status is the first refused lane's
/// fragment error (0 refused: `MLAB_STATUS_OK`). On any other error `*refused` is unchanged.
/// Mask 0 inserts nothing: `MLAB_STATUS_OK` and `*refused = 0` whatever `x`, `y` and
/// `fragments` (not read; may be null).
///
/// # Safety
/// `fb` as for `mlab_insert_straight`; `fragments` is null or valid for a read of one
/// `MlabFragmentSpan`; `refused` is null or valid for a write of one byte.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn mlab_insert_span_straight(
    fb: *mut MlabFramebuffer,
    x: u32,
    y: u32,
    fragments: *const MlabFragmentSpan,
    mask: u8,
    refused: *mut u8,
) -> MlabStatus {
    // SAFETY: the caller's guarantee, passed on.
    unsafe { insert_span(fb, x, y, fragments, mask, refused, true) }
}

/// `mlab_insert_span_straight` with premultiplied color.
///
/// # Safety
/// As `mlab_insert_span_straight`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn mlab_insert_span_premultiplied(
    fb: *mut MlabFramebuffer,
    x: u32,
    y: u32,
    fragments: *const MlabFragmentSpan,
    mask: u8,
    refused: *mut u8,
) -> MlabStatus {
    // SAFETY: the caller's guarantee, passed on.
    unsafe { insert_span(fb, x, y, fragments, mask, refused, false) }
}

/// `mlab_insert_span_straight` with a stable key per lane (`fragments->key[i]`, as
/// `mlab_insert_straight_keyed`): byte-identical to `mlab_insert_straight_keyed` lane by
/// lane, in lane order. The same checks, statuses and `*refused`.
///
/// # Safety
/// As `mlab_insert_span_straight`, `fragments` null or valid for a read of one
/// `MlabFragmentSpanKeyed`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn mlab_insert_span_straight_keyed(
    fb: *mut MlabFramebuffer,
    x: u32,
    y: u32,
    fragments: *const MlabFragmentSpanKeyed,
    mask: u8,
    refused: *mut u8,
) -> MlabStatus {
    // SAFETY: the caller's guarantee, passed on.
    unsafe { insert_span(fb, x, y, fragments, mask, refused, true) }
}

/// `mlab_insert_span_straight_keyed` with premultiplied color.
///
/// # Safety
/// As `mlab_insert_span_straight_keyed`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn mlab_insert_span_premultiplied_keyed(
    fb: *mut MlabFramebuffer,
    x: u32,
    y: u32,
    fragments: *const MlabFragmentSpanKeyed,
    mask: u8,
    refused: *mut u8,
) -> MlabStatus {
    // SAFETY: the caller's guarantee, passed on.
    unsafe { insert_span(fb, x, y, fragments, mask, refused, false) }
}
