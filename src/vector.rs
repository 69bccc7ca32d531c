//! The lane traits of the inserts: what Listing 1 ([`crate::mlab`]) and Listing 2
//! ([`crate::hybrid`]) are written over, and their width-1 implementations (one pixel: [`Row`]
//! and the tails), which are the scalar kernel. The 8-wide implementations are in
//! `lanes/w256.rs` (and the HT one with AVX-512 in `lanes/w512.rs`). The float lane trait of
//! the resolve, [`crate::resolve::FloatLanes`], stays beside the resolve: here it would close
//! an import loop (this file names the tails, whose resolve is written over it).

use crate::arith::Arithmetic;
use crate::row::Row;
use crate::tail::TailFormat;

/// Rows of one or more pixels, one pixel per lane: what Listings 1 and 2 are written over.
pub(crate) trait RowLanes: Copy {
    /// Per-lane condition.
    type Mask: Copy + core::ops::BitAnd<Output = Self::Mask>;
    /// Per-lane HT tail of layout `T`.
    type Tail<T: TailFormat>: Copy;
    /// Per-lane hash of the inserted fragment ([`crate::fragment_hash`]), in the form
    /// the merge reads it.
    type Hash: Copy;
    /// `self.z <= other.z` in IEEE f32 (false when either is NaN).
    fn depth_le(self, other: Self) -> Self::Mask;
    /// `if mask { a } else { b }` per lane.
    fn select(mask: Self::Mask, a: Self, b: Self) -> Self;
    /// The swap of Listing 1's bubble step: `(select(mask, a, b), select(mask, b, a))`, the
    /// row stored back to the slot `b` was loaded from and the row carried to the next layer.
    /// A lane type may compute the stored one with other instructions so that the compiler
    /// cannot fold its select and the store into a masked store (`vmaskmovpd`, which AMD CPUs
    /// microcode; `benches/asm/check.sh` fails on it).
    #[inline(always)]
    fn swap(mask: Self::Mask, a: Self, b: Self) -> (Self, Self) {
        (Self::select(mask, a, b), Self::select(mask, b, a))
    }
    /// Eq. 7-8 per lane in the arithmetic `A` ([`Arithmetic::merge`]).
    fn merge<A: Arithmetic>(front: Self, back: Self, h: Self::Hash) -> Self;
    /// Per lane, `merge(a, b)` where `a_first`, else `merge(b, a)`: the last step of
    /// Listing 1.
    #[inline(always)]
    fn merge_pair<A: Arithmetic>(a_first: Self::Mask, a: Self, b: Self, h: Self::Hash) -> Self {
        Self::merge::<A>(Self::select(a_first, a, b), Self::select(a_first, b, a), h)
    }
    /// [`TailFormat::add`] per lane.
    fn tail_add<T: TailFormat>(tail: Self::Tail<T>, row: Self) -> Self::Tail<T>;
    /// `if mask { a } else { b }` per lane, for tails.
    fn select_tail<T: TailFormat>(mask: Self::Mask, a: Self::Tail<T>, b: Self::Tail<T>) -> Self::Tail<T>;
}

impl RowLanes for Row {
    type Mask = bool;
    type Tail<T: TailFormat> = T;
    type Hash = u32;
    #[inline(always)]
    fn depth_le(self, other: Self) -> bool {
        self.depth() <= other.depth()
    }
    #[inline(always)]
    fn select(mask: bool, a: Self, b: Self) -> Self {
        // Branchless (cmov): a data-dependent branch mispredicts on every unsorted stream.
        Row::from_le_u64(core::hint::select_unpredictable(mask, a.to_le_u64(), b.to_le_u64()))
    }
    #[inline(always)]
    fn merge<A: Arithmetic>(front: Self, back: Self, h: u32) -> Self {
        A::merge(front, back, h)
    }
    #[inline(always)]
    fn tail_add<T: TailFormat>(tail: T, row: Self) -> T {
        let mut t = tail;
        t.add(row);
        t
    }
    #[inline(always)]
    fn select_tail<T: TailFormat>(mask: bool, a: T, b: T) -> T {
        core::hint::select_unpredictable(mask, a, b)
    }
}

/// Where the rows of one layer live: Listings 1 and 2 load a layer, update it, and store it
/// back before the next one, so only one layer and the carried row are ever held in
/// registers (an array of `M` layers would spill, and copy, at large `M`).
pub(crate) trait Slot<L> {
    /// Read the layer.
    fn load(&self) -> L;
    /// Write the layer.
    fn store(&mut self, value: L);
}

impl Slot<Row> for Row {
    #[inline(always)]
    fn load(&self) -> Row {
        *self
    }
    #[inline(always)]
    fn store(&mut self, value: Row) {
        *self = value;
    }
}

impl<T: TailFormat> Slot<T> for T {
    #[inline(always)]
    fn load(&self) -> T {
        *self
    }
    #[inline(always)]
    fn store(&mut self, value: T) {
        *self = value;
    }
}

/// A lane type that holds one layer of a span: 8 whole rows, read and written at once. Its
/// [`Slot`]s are a layer of rows and a layer of tails (8 bytes each, the same bits).
pub(crate) trait Layer8: Copy {
    /// The lanes of 8 rows.
    fn from_rows(rows: [Row; 8]) -> Self;
    /// The 8 rows of the lanes.
    fn to_rows(self) -> [Row; 8];
}

impl<L: Layer8> Slot<L> for [Row; 8] {
    #[inline(always)]
    fn load(&self) -> L {
        L::from_rows(*self)
    }
    #[inline(always)]
    fn store(&mut self, value: L) {
        *self = value.to_rows();
    }
}

impl<L: Layer8, T: TailFormat> Slot<L> for [T; 8] {
    #[inline(always)]
    fn load(&self) -> L {
        L::from_rows(bytemuck::cast(*self))
    }
    #[inline(always)]
    fn store(&mut self, value: L) {
        *self = bytemuck::cast(value.to_rows());
    }
}
