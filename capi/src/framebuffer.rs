//! The framebuffer struct (`MlabFramebuffer`): its private fields and their checksum (`seal`),
//! the check that a pointer to it is an initialized, unchanged one (`state`), the rows of
//! storage of a size (`rows_needed`), and the kernel's typed span grid rebuilt over its rows
//! for one call (`with_grid!`).

use mlab::{Layers, Row};

use crate::boundary::check_ptr;
use crate::status::MlabStatus;
use crate::types::{MLAB_METHOD_HYBRID, MLAB_METHOD_MLAB, MlabMethod, MlabRow};

/// A framebuffer: the state `mlab_framebuffer_init` fills, over storage the caller owns.
/// Declare it anywhere (stack, heap, inside another struct); **its fields are private**: read
/// and write none of them. It owns nothing and may be copied (copies view the same rows).
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct MlabFramebuffer {
    /// Private: the first row of the storage.
    pub(crate) storage: *mut MlabRow,
    /// Private: rows of storage.
    pub(crate) storage_rows: usize,
    /// Private: width in pixels.
    pub(crate) width: u32,
    /// Private: height in lines.
    pub(crate) height: u32,
    /// Private: the id of pixel `(0, 0)` in the hashes that seed the dithers: 0, or for a
    /// band the id of its first pixel in the whole framebuffer (`first_line * width`).
    pub(crate) first: u32,
    /// Private: set by a successful init or band: the kind
    /// (`layers - 1 + 8 * method + 16 * arithmetic`) in its low 5 bits, above them a
    /// checksum of every field, which every call checks.
    pub(crate) tag: u32,
}

#[cfg(target_pointer_width = "64")]
const _: () = assert!(size_of::<MlabFramebuffer>() == 32 && align_of::<MlabFramebuffer>() == 8);

/// The bits of `MlabFramebuffer::tag` that hold the kind (0 to 31: `with_grid!`'s index).
const KIND_MASK: u32 = 31;

/// The seed of the checksum in `tag` ("MLAB"): a zeroed struct does not pass.
const MAGIC: u64 = 0x4d4c_4142;

/// The `tag` of a state with these fields: `kind` in the low bits, above them a checksum of
/// every field (multiply-xor rounds: each field changes the whole product), so that a struct
/// that was not filled by init or band, or whose fields were changed since (a size changed
/// with its storage length, a pointer moved), is refused before its rows are touched. A
/// checksum, not a proof: a change goes unnoticed with probability 2^-27.
#[inline(always)]
pub(crate) fn seal(storage: *mut MlabRow, storage_rows: usize, width: u32, height: u32, first: u32, kind: u32) -> u32 {
    const K: u64 = 0x9e37_79b9_7f4a_7c15;
    let words = [
        storage.addr() as u64,
        storage_rows as u64,
        u64::from(width) << 32 | u64::from(height),
        u64::from(first) << 32 | u64::from(kind),
    ];
    let h = words.iter().fold(MAGIC, |h, &w| (h ^ w).wrapping_mul(K));
    (h >> 32) as u32 & !KIND_MASK | kind
}

impl MlabFramebuffer {
    pub(crate) const ZEROED: MlabFramebuffer = MlabFramebuffer {
        storage: core::ptr::null_mut(),
        storage_rows: 0,
        width: 0,
        height: 0,
        first: 0,
        tag: 0,
    };

    /// The kind, 0 to 31 (`layers - 1 + 8 * method + 16 * arithmetic`).
    #[inline(always)]
    pub(crate) fn kind(&self) -> u32 {
        self.tag & KIND_MASK
    }

    /// The rows of the storage as the kernel's rows, for the duration of one call.
    ///
    /// # Safety
    /// `self` was filled by `mlab_framebuffer_init` or `mlab_framebuffer_band` (as `state`
    /// checks), and the caller of the exported function guarantees that its rows are valid,
    /// writable and used by nothing else for `'r`, which ends before that function returns.
    #[inline(always)]
    pub(crate) unsafe fn rows<'r>(&self) -> &'r mut [Row] {
        // SAFETY: `storage` was checked non-null and 8-byte aligned by `mlab_framebuffer_init`
        // (or derived from such a pointer by `mlab_framebuffer_band`), and `storage_rows`
        // rows of it fit in isize::MAX bytes; the caller guarantees that these rows are
        // valid, writable and not used elsewhere during this call. Any 8 bytes are a valid
        // `Row` (it is Pod), and `MlabRow` has its size and alignment (asserted in
        // `types.rs`).
        unsafe { core::slice::from_raw_parts_mut(self.storage.cast::<Row>(), self.storage_rows) }
    }
}

/// The kernel's `Layers` of a method and a size (size not checked here).
fn layers_of(method: MlabMethod, layers: u32) -> Result<Layers, MlabStatus> {
    let n = layers as usize;
    match method {
        MLAB_METHOD_MLAB => Ok(Layers::Mlab(n)),
        MLAB_METHOD_HYBRID => Ok(Layers::Hybrid(n)),
        _ => Err(MlabStatus::InvalidArgument),
    }
}

/// Rows of storage of a framebuffer, every argument checked (sizes 0 refused).
pub(crate) fn rows_needed(method: MlabMethod, layers: u32, width: u32, height: u32) -> Result<usize, MlabStatus> {
    let l = layers_of(method, layers)?;
    if width == 0 || height == 0 {
        return Err(MlabStatus::ZeroSize);
    }
    let rows = l.rows_needed(width, height)?;
    // The storage must be addressable as one Rust slice: at most isize::MAX bytes.
    if rows > isize::MAX as usize / size_of::<Row>() {
        return Err(MlabStatus::SizeOverflow);
    }
    Ok(rows)
}

/// The initialized framebuffer struct behind `fb`, its fields unchanged since (`seal`).
///
/// # Safety
/// `fb` is null or points to a readable `MlabFramebuffer` (initialized or not).
#[inline(always)]
pub(crate) unsafe fn state<'s>(fb: *const MlabFramebuffer) -> Result<&'s MlabFramebuffer, MlabStatus> {
    check_ptr(fb, align_of::<MlabFramebuffer>())?;
    // SAFETY: non-null and aligned (checked); readable (the caller's guarantee).
    let s = unsafe { &*fb };
    if s.tag != seal(s.storage, s.storage_rows, s.width, s.height, s.first, s.kind()) {
        return Err(MlabStatus::NotInitialized);
    }
    Ok(s)
}

/// `$body` with `$fb` bound to the kernel's typed span grid over the rows of `$s` (an
/// initialized [`MlabFramebuffer`]): `SpanFramebuffer<M, A>` or `HybridSpanFramebuffer<K, A>`,
/// the grids that `DynFramebuffer` dispatches to, chosen by one `match` on the kind stored
/// at init. The view is rebuilt for the call (`Grid::new`: a length check, then the band's
/// first pixel id, `Grid::with_first_pixel`, so that a band hashes its pixels as the whole
/// framebuffer does) and dropped at its end. Not `DynFramebuffer::new` itself: with its choice of the variant from `Layers`
/// (16 comparisons) and then its `match`, a per-pixel insert through this API ran 373
/// instructions, against 313 with this macro and 233 for the Rust loop over
/// `DynFramebuffer::insert` (MLAB 4, callgrind; `docs/performance.md`, "C API"). The
/// per-pixel inserts go further (`insert_one`).
macro_rules! with_grid {
    ($s:expr, $fb:ident => $body:expr) => {
        $crate::framebuffer::with_grid!(@arms $s, $fb, $body;
            0 SpanFramebuffer<'_, 1, Unbiased>, 1 SpanFramebuffer<'_, 2, Unbiased>,
            2 SpanFramebuffer<'_, 3, Unbiased>, 3 SpanFramebuffer<'_, 4, Unbiased>,
            4 SpanFramebuffer<'_, 5, Unbiased>, 5 SpanFramebuffer<'_, 6, Unbiased>,
            6 SpanFramebuffer<'_, 7, Unbiased>, 7 SpanFramebuffer<'_, 8, Unbiased>,
            8 HybridSpanFramebuffer<'_, 1, Unbiased>, 9 HybridSpanFramebuffer<'_, 2, Unbiased>,
            10 HybridSpanFramebuffer<'_, 3, Unbiased>, 11 HybridSpanFramebuffer<'_, 4, Unbiased>,
            12 HybridSpanFramebuffer<'_, 5, Unbiased>, 13 HybridSpanFramebuffer<'_, 6, Unbiased>,
            14 HybridSpanFramebuffer<'_, 7, Unbiased>, 15 HybridSpanFramebuffer<'_, 8, Unbiased>,
            16 SpanFramebuffer<'_, 1, Paper>, 17 SpanFramebuffer<'_, 2, Paper>,
            18 SpanFramebuffer<'_, 3, Paper>, 19 SpanFramebuffer<'_, 4, Paper>,
            20 SpanFramebuffer<'_, 5, Paper>, 21 SpanFramebuffer<'_, 6, Paper>,
            22 SpanFramebuffer<'_, 7, Paper>, 23 SpanFramebuffer<'_, 8, Paper>,
            24 HybridSpanFramebuffer<'_, 1, Paper>, 25 HybridSpanFramebuffer<'_, 2, Paper>,
            26 HybridSpanFramebuffer<'_, 3, Paper>, 27 HybridSpanFramebuffer<'_, 4, Paper>,
            28 HybridSpanFramebuffer<'_, 5, Paper>, 29 HybridSpanFramebuffer<'_, 6, Paper>,
            30 HybridSpanFramebuffer<'_, 7, Paper>, 31 HybridSpanFramebuffer<'_, 8, Paper>)
    };
    (@arms $s:expr, $fb:ident, $body:expr; $($k:literal $t:ty),*) => {{
        use ::mlab::{HybridSpanFramebuffer, Paper, SpanFramebuffer, Unbiased};
        use $crate::framebuffer::MlabFramebuffer;
        use $crate::status::MlabStatus;
        let s: &MlabFramebuffer = $s;
        // SAFETY: `s` was filled by `mlab_framebuffer_init` or `mlab_framebuffer_band` (or is
        // the state that init is about to write), and the caller guarantees its rows for this
        // call; the slice lives only until this block ends.
        let rows = unsafe { s.rows() };
        match s.kind() {
            $($k => {
                #[allow(unused_mut)]
                let mut $fb = <$t>::new(rows, s.width, s.height)?.with_first_pixel(s.first);
                $body
            })*
            _ => Err(MlabStatus::NotInitialized),
        }
    }};
}

pub(crate) use with_grid;
