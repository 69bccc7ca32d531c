//! Multi-Layer Alpha Blending: the blending array and Listing 1 of Salvi & Vaidyanathan (2014).
//!
//! ```text
//! MLAB(in Fragment f, inout Fragment B[m+1])          // Listing 1 (paper, section 4)
//!   for i in 0..m:                                    // 1-pass bubble sort
//!     if f.z <= B[i].z: swap(B[i], f)
//!   B[m-1] = merge(B[m-1], f)                         // f is now the row pushed out (B[m])
//!
//! merge(front, back):                                 // Eq. 7 and 8, section 3.2
//!   A = A_front + A_back * T_front
//!   T = T_front * T_back
//!   z = z_front                                       // Paper; Unbiased: the opacity-weighted
//!                                                     // depth of the two (crate::arith)
//! ```
//!
//! Arithmetic: the merge runs in exact unorm8 integers, in one of two arithmetics
//! ([`crate::arith`]): the default [`Unbiased`] rounds each product `floor((a * b + d) / 255)`
//! with a dither `d` from the inserted fragment's hash in its pixel, also when the rows merged
//! are two older ones (`docs/layout.md`; no transmittance stall on faint layers), the
//! paper's [`Paper`](crate::Paper) rounds to nearest. Both are deterministic, need no
//! floating point, and a shader reproduces them bit for bit. Merging with the empty row is
//! the identity in both, so an array that is not full needs no special case.
//!
//! Invariants kept by [`insert_with`] for any stream of valid fragments (finite depth): rows
//! sorted by depth front to back (non-decreasing `z`), rows at `z = +infinity` are
//! [`Row::EMPTY`] and only at the back.

use core::marker::PhantomData;

use crate::arith::{Arithmetic, Unbiased};
use crate::fragment::Fragment;
use crate::resolve::{Resolved, resolve_rows};
use crate::row::Row;
use crate::vector::{RowLanes, Slot};

/// Compile-time check that a blending array has at least one row.
pub(crate) struct AtLeastOne<const M: usize>;
impl<const M: usize> AtLeastOne<M> {
    pub(crate) const OK: () = assert!(M >= 1, "an MLAB blending array needs at least one row (M >= 1)");
}

/// Listing 1 on a blending array of `M` rows in the arithmetic `A`: insert `row`, then
/// merge the last two rows.
///
/// The comparison is the paper's `f.z <= B[i].z` in IEEE f32: a new fragment goes in front
/// of rows at equal depth (so coplanar fragments blend like OVER in submission order), and
/// a NaN depth (only possible in rows read from arbitrary bytes) never compares true.
///
/// Rows read from arbitrary bytes (unsorted, NaN depth) are processed by the same steps;
/// the result is deterministic and never panics, but the invariants only hold if they held
/// before.
///
/// The merge of [`Unbiased`] is seeded by the row's content key ([`row_hash`] of pixel 0),
/// which changes with the row's depth: [`insert_hashed`] takes the hash of a keyed fragment
/// instead ([`Fragment::hash`]).
#[inline]
pub fn insert_with<A: Arithmetic, const M: usize>(rows: &mut [Row; M], row: Row) {
    insert_lanes::<A, _, _, M>(rows, row, true, row_hash(row, 0));
}

/// Listing 1 as [`insert_with`], the merge seeded by `h`, the inserted fragment's hash
/// ([`Fragment::hash`], [`crate::fragment_hash`]).
#[inline]
pub fn insert_hashed<A: Arithmetic, const M: usize>(rows: &mut [Row; M], row: Row, h: u32) {
    insert_lanes::<A, _, _, M>(rows, row, true, h);
}

/// The hash of an already quantized row in pixel `pixel`, with its content key (the XOR of
/// its two words, [`Row::words`]): `fragment_hash(word0 ^ word1, pixel)`. What inserts of
/// rows ([`insert_with`], [`Framebuffer::insert_row`](crate::Framebuffer::insert_row)) seed
/// the merge with.
#[inline(always)]
#[must_use]
pub const fn row_hash(row: Row, pixel: u32) -> u32 {
    let [w0, w1] = row.words();
    crate::hash::fragment_hash(w0 ^ w1, pixel)
}

/// Listing 1, written once for every lane width (a [`Row`] is one lane; see
/// [`crate::lanes`]): lanes where `on` is false are left untouched. The swap of the listing
/// is two selects on the same condition, so this is the listing step for step, for any rows.
#[inline(always)]
pub(crate) fn insert_lanes<A: Arithmetic, L: RowLanes, S: Slot<L>, const M: usize>(
    b: &mut [S; M],
    fragment: L,
    on: L::Mask,
    h: L::Hash,
) {
    let () = AtLeastOne::<M>::OK;
    let mut f = fragment;
    // 1-pass bubble sort to insert fragment, one layer at a time.
    for (i, slot) in b.iter_mut().enumerate() {
        let row = slot.load();
        let swap = f.depth_le(row) & on; // if (f.z <= B[i].z)
        if i + 1 < M {
            // B[i] = f; f = temp.
            let (front, next) = L::swap(swap, f, row);
            slot.store(front);
            f = next;
        } else {
            // Compression (merge last two rows): the row pushed out (`f` after the swap, B[m]
            // in the listing) merged behind `front`.
            let front = L::select(swap, f, row);
            slot.store(L::select(on, L::merge_pair::<A>(swap, f, row, h), front));
        }
    }
}

/// A blending array of `M >= 1` rows (`8 * M` bytes), sorted front to back.
///
/// `M = 0` is a compile-time error.
///
/// ```
/// use mlab::glam::Vec3;
/// use mlab::{BlendingArray, Fragment};
/// let mut b = BlendingArray::<2>::new();
/// // Three fragments out of order into two rows: the back two are merged.
/// for (c, a, z) in [(Vec3::X, 0.5, 2.0), (Vec3::Y, 0.5, 1.0), (Vec3::Z, 0.5, 3.0)] {
///     b.insert(&Fragment::straight(c, a, z)?);
/// }
/// let px = b.resolve().over(Vec3::ZERO);
/// // Front to back: green (1.0), red (2.0), blue (3.0), each alpha 0.5.
/// assert!((px - Vec3::new(0.25, 0.5, 0.125)).abs().max_element() < 3.0 / 255.0);
/// # Ok::<(), mlab::FragmentError>(())
/// ```
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
#[repr(transparent)]
pub struct BlendingArray<const M: usize, A: Arithmetic = Unbiased> {
    rows: [Row; M],
    arithmetic: PhantomData<A>,
}

impl<const M: usize, A: Arithmetic> BlendingArray<M, A> {
    /// An array of empty rows.
    pub const fn new() -> Self {
        let () = AtLeastOne::<M>::OK;
        BlendingArray {
            rows: [Row::EMPTY; M],
            arithmetic: PhantomData,
        }
    }

    /// An array over given rows (for example read back from a GPU buffer). Any rows are
    /// accepted; see [`insert_with`] for what unsorted rows do.
    pub const fn from_rows(rows: [Row; M]) -> Self {
        let () = AtLeastOne::<M>::OK;
        BlendingArray {
            rows,
            arithmetic: PhantomData,
        }
    }

    /// The rows, front to back.
    pub const fn rows(&self) -> &[Row; M] {
        &self.rows
    }

    /// Insert a validated fragment (quantized here, once, by `A`) with Listing 1, as the
    /// fragment of pixel 0 ([`insert_at`](Self::insert_at)).
    #[inline]
    pub fn insert(&mut self, fragment: &Fragment) {
        self.insert_at(fragment, 0);
    }

    /// Insert a validated fragment into the array of pixel `pixel` (any id the caller picks
    /// for this array: a pixel index, a ray index), quantized and merged with the hash
    /// [`Fragment::hash`]`(pixel)`: with a keyed fragment ([`Fragment::with_key`]) and a
    /// stable `pixel`, [`Unbiased`]'s dithers do not change from one frame to the next.
    ///
    /// ```
    /// use mlab::glam::Vec3;
    /// use mlab::{BlendingArray, Fragment};
    /// let mut a = BlendingArray::<2>::new();
    /// let (x, y, width) = (3, 5, 640);
    /// for (prim, z) in [(11u32, 1.0), (12, 2.0), (13, 3.0)] {
    ///     let f = Fragment::straight(Vec3::splat(0.5), 0.04, z)?.with_key(prim);
    ///     a.insert_at(&f, y * width + x);
    /// }
    /// assert!(a.resolve().transmittance < 1.0);
    /// # Ok::<(), mlab::FragmentError>(())
    /// ```
    #[inline]
    pub fn insert_at(&mut self, fragment: &Fragment, pixel: u32) {
        let h = fragment.hash(pixel);
        insert_hashed::<A, M>(&mut self.rows, A::quantize(fragment, h), h);
    }

    /// Insert an already quantized row with Listing 1 ([`insert_with`]: seeded by the row's
    /// content, [`row_hash`] of pixel 0).
    #[inline]
    pub fn insert_row(&mut self, row: Row) {
        insert_with::<A, M>(&mut self.rows, row);
    }

    /// Resolve (paper Eq. 5 and 6), see [`resolve_rows`].
    #[inline]
    pub fn resolve(&self) -> Resolved {
        resolve_rows(&self.rows)
    }
}

impl<const M: usize, A: Arithmetic> Default for BlendingArray<M, A> {
    fn default() -> Self {
        Self::new()
    }
}
