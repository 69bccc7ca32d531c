//! The framebuffer's lifecycle: the storage it needs (`mlab_rows_needed`), its init over the
//! caller's storage, a band of its lines for another thread, and the clear that starts a
//! frame.

use mlab::Framebuffer;

use crate::boundary::{check_ptr, guard};
use crate::framebuffer::{MlabFramebuffer, rows_needed, seal, state, with_grid};
use crate::status::MlabStatus;
use crate::types::{MLAB_ARITHMETIC_PAPER, MlabArithmetic, MlabMethod, MlabRow};

/// Writes to `*rows` the rows of storage (`MlabRow`, 8 bytes each) of a framebuffer of
/// `width x height` pixels: `ceil(width / 8) * 8 * height * R`, `R = layers` for MLAB and
/// `layers + 1` for HT (pixels are stored in 8-pixel spans). `layers` is 1 to 8; width and
/// height are at least 1. On error `*rows` is unchanged.
///
/// # Safety
/// `rows` is null or valid for a write of one `size_t`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn mlab_rows_needed(
    method: MlabMethod,
    layers: u32,
    width: u32,
    height: u32,
    rows: *mut usize,
) -> MlabStatus {
    guard(|| {
        check_ptr(rows, align_of::<usize>())?;
        let n = rows_needed(method, layers, width, height)?;
        // SAFETY: non-null and aligned (checked), writable (the caller's guarantee).
        unsafe { rows.write(n) };
        Ok(())
    })
}

/// Fills `*fb` with a framebuffer of `width x height` pixels over `storage` (exactly
/// `mlab_rows_needed` rows, 8-byte aligned: `malloc` and `calloc` memory is), in the
/// method, size and arithmetic given, and clears it (every pixel empty). `storage` need not
/// be initialized. On error after `fb` was checked, `*fb` is marked uninitialized (later
/// calls with it return `MLAB_STATUS_NOT_INITIALIZED`) and the storage is not touched.
///
/// # Safety
/// `fb` is null or valid for a write of one `MlabFramebuffer`; `storage` is null or valid
/// for reads and writes of `storage_rows` rows, now and for every later call with `*fb` (or
/// a copy, or a band of it), and not used by anything else during those calls.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn mlab_framebuffer_init(
    fb: *mut MlabFramebuffer,
    method: MlabMethod,
    layers: u32,
    arithmetic: MlabArithmetic,
    storage: *mut MlabRow,
    storage_rows: usize,
    width: u32,
    height: u32,
) -> MlabStatus {
    guard(|| {
        check_ptr(fb, align_of::<MlabFramebuffer>())?;
        // SAFETY: non-null and aligned (checked); writable (the caller's guarantee).
        unsafe { fb.write(MlabFramebuffer::ZEROED) };
        if arithmetic > MLAB_ARITHMETIC_PAPER {
            return Err(MlabStatus::InvalidArgument);
        }
        let expected = rows_needed(method, layers, width, height)?;
        check_ptr(storage, align_of::<MlabRow>())?;
        if storage_rows != expected {
            return Err(MlabStatus::StorageLength);
        }
        // The kind is in 0..32: method is 0 or 1, layers 1 to 8, arithmetic 0 or 1 (checked
        // above).
        let kind = (layers - 1) | method << 3 | arithmetic << 4;
        let state = MlabFramebuffer {
            storage,
            storage_rows,
            width,
            height,
            first: 0,
            tag: seal(storage, storage_rows, width, height, 0, kind),
        };
        with_grid!(&state, f => {
            f.clear();
            Ok::<(), MlabStatus>(())
        })?;
        // SAFETY: as above.
        unsafe { fb.write(state) };
        Ok(())
    })
}

/// Fills `*band` with a view of lines `first_line .. first_line + lines` of `*fb` (the same
/// width, method and arithmetic; its line 0 is `first_line` of `fb`), for another thread:
/// bands that do not overlap may be used at the same time, one thread each. An insert at
/// `(x, y)` of the band writes the bytes of the same insert at `(x, first_line + y)` of
/// `fb`: the band keeps the whole framebuffer's pixel ids, which seed the dithers (a band
/// of a band too). The rows are not changed (no clear). On error after `band` was checked,
/// `*band` is marked uninitialized.
///
/// # Safety
/// `fb` is null or points to a readable `MlabFramebuffer`; `band` is null or valid for a
/// write of one, and is not `fb`'s struct in use by another thread.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn mlab_framebuffer_band(
    fb: *const MlabFramebuffer,
    first_line: u32,
    lines: u32,
    band: *mut MlabFramebuffer,
) -> MlabStatus {
    guard(|| {
        // SAFETY: the caller's guarantee on `fb`.
        let s = *unsafe { state(fb) }?;
        check_ptr(band, align_of::<MlabFramebuffer>())?;
        // SAFETY: non-null and aligned (checked); writable (the caller's guarantee).
        unsafe { band.write(MlabFramebuffer::ZEROED) };
        if lines == 0 {
            return Err(MlabStatus::ZeroSize);
        }
        if first_line as u64 + lines as u64 > s.height as u64 {
            return Err(MlabStatus::OutOfBounds);
        }
        // Spans store lines one after the other: a band is a contiguous run of rows.
        let line_rows = rows_needed(s.kind() >> 3 & 1, (s.kind() & 7) + 1, s.width, 1)?;
        if line_rows.checked_mul(s.height as usize) != Some(s.storage_rows) {
            return Err(MlabStatus::NotInitialized);
        }
        // Both at most `storage_rows` (checked just above): no overflow.
        let offset = first_line as usize * line_rows;
        let rows = lines as usize * line_rows;
        // `wrapping_add`: no dereference here; in bounds of the storage (checked above), so
        // the pointer keeps the storage's provenance and alignment.
        let storage = s.storage.wrapping_add(offset);
        // The id of its first pixel in the whole framebuffer (wrapping, as the kernel's
        // `split_lines`): a band of a band keeps counting from the whole's.
        let first = s.first.wrapping_add(first_line.wrapping_mul(s.width));
        let sub = MlabFramebuffer {
            storage,
            storage_rows: rows,
            height: lines,
            first,
            tag: seal(storage, rows, s.width, lines, first, s.kind()),
            ..s
        };
        // SAFETY: as above.
        unsafe { band.write(sub) };
        Ok(())
    })
}

/// Clears every pixel of `*fb` (empty rows, empty HT tails): the start of a frame.
///
/// # Safety
/// `fb` is null or points to a readable `MlabFramebuffer` whose storage satisfies the
/// guarantees of `mlab_framebuffer_init`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn mlab_framebuffer_clear(fb: *mut MlabFramebuffer) -> MlabStatus {
    guard(|| {
        // SAFETY: the caller's guarantee on `fb`.
        let s = unsafe { state(fb) }?;
        with_grid!(s, f => {
            f.clear();
            Ok(())
        })
    })
}
