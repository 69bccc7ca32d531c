//! How the pixels of a [`Grid`](super::Grid) are laid out: [`PixelMajor`] or [`Spans`]. The
//! arrangements own the index maths, the units of a line, span rotation and the only
//! gather/scatter of the storage layer: a kind's leaf (`pixel.rs`) is handed a layer-major
//! span, `H` head layers and `T` tail layers of `[Row; 8]`, borrowed from span storage or
//! gathered from 1 to 8 pixel-major pixels (and the lanes that are on scattered back), and a
//! pixel's rows, borrowed from pixel-major storage or gathered from its lane. The const
//! sizes come from the kind (`[[Row; 8]; P::ROWS]` cannot be named on stable Rust): MLAB
//! passes `H = M, T = 0`, HT `H = K, T = 1` (the tails).

use core::fmt::Debug;

use super::dims::{Dims, SpanAt};
use crate::lanes::{LANES, LANES_U32};
use crate::row::Row;

impl crate::sealed::Sealed for PixelMajor {}
impl crate::sealed::Sealed for Spans {}

/// Pixel-major storage: pixel `(x, y)` owns the rows
/// `[(y * width + x) * R, (y * width + x + 1) * R)`, `R` = [`Pixel::ROWS`](super::Pixel::ROWS) (an HT pixel's last slot holds its tail's bytes).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct PixelMajor;

/// 8-pixel spans, layer-major: slot `j` of pixel `(x, y)` is row
/// `((y * spans + x / 8) * R + j) * 8 + x % 8`, `spans = ceil(width / 8)`; for HT the `K`
/// head layers come first, then the 8 tails. Lanes past the right edge are padding (kept empty).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct Spans;

/// The 8 lanes of a span insert: a row and its hash per lane, and the lanes that are on.
/// Public in a private module, as [`SpanAt`]: the batcher's flush hands it on.
#[derive(Clone, Copy, Debug)]
pub struct SpanRows<'r> {
    pub(crate) rows: &'r [Row; LANES],
    pub(crate) hashes: &'r [u32; LANES],
    pub(crate) mask: u8,
}

/// A layer-major span: `N` layers of 8 rows.
pub(crate) type Layers8<const N: usize> = [[Row; LANES]; N];

// The leaves below are traits, not closures or functions passed as values: a closure, or
// a function through its `FnOnce` shim, holding Listing 1 was a call of its own in another
// codegen unit (MLAB inserts 1.06-1.11x the instructions, callgrind x86-64-v3); a trait's
// `#[inline(always)]` method is inlined.

/// What a span insert does to one unit of storage (a kind's span insert).
pub(crate) trait InsertUnit {
    /// Insert the lanes of `span` that are on into `unit`.
    fn insert(unit: &mut [Row], span: SpanRows<'_>);
}

/// A kind's insert of one pixel: on its `H` head and `T` tail rows, or on its lane of a
/// stored span.
pub(crate) trait PixelLeaf<const H: usize, const T: usize> {
    /// On the pixel's rows.
    fn pixel(self, head: &mut [Row; H], tail: &mut [Row; T]);
    /// On lane `lane` of a stored span.
    fn lane(self, head: &mut Layers8<H>, tail: &mut Layers8<T>, lane: usize);
}

/// A kind's leaf on a layer-major span.
pub(crate) trait SpanLeaf<const H: usize, const T: usize> {
    /// On the span's head and tail layers.
    fn span(self, head: &mut Layers8<H>, tail: &mut Layers8<T>);
}

/// How the pixels of a [`Grid`](super::Grid) are laid out: [`PixelMajor`] or [`Spans`]
/// (sealed). The hidden items are the storage layer's index maths and views, each written
/// once for both arrangements (`SPANS` is a constant: each grid compiles one branch).
// `Dims` is the crate's own: the trait is sealed, no other crate implements or calls it.
#[allow(private_interfaces, private_bounds)]
pub trait Arrangement: crate::sealed::Sealed + Copy + Debug + Default + Send + Sync + 'static {
    /// Whether pixels are stored in 8-pixel layer-major spans.
    const SPANS: bool;

    /// Rows of one line of `rows` slots per pixel.
    #[doc(hidden)]
    fn line_rows(d: Dims, rows: usize) -> Option<usize> {
        let pixels = if Self::SPANS {
            d.spans.checked_mul(LANES)?
        } else {
            d.width as usize
        };
        pixels.checked_mul(rows)
    }

    /// Storage index of slot `j` of pixel `(x, y)` (checked before), `n` slots per pixel.
    #[doc(hidden)]
    fn slot(d: Dims, n: usize, x: u32, y: u32, j: usize) -> usize {
        if Self::SPANS {
            (d.span_at(x, y).index * n + j) * LANES + x as usize % LANES
        } else {
            d.index_unchecked(x, y) * n + j
        }
    }

    /// Which slot of its pixel storage index `i` holds, `n` slots per pixel.
    #[doc(hidden)]
    fn slot_of(i: usize, n: usize) -> usize {
        if Self::SPANS { i / LANES % n } else { i % n }
    }

    /// Index in the unit of one span of slot `j` of lane `lane`, `n` slots per pixel.
    #[doc(hidden)]
    #[inline(always)]
    fn unit_slot(n: usize, lane: usize, j: usize) -> usize {
        if Self::SPANS { j * LANES + lane } else { lane * n + j }
    }

    /// The storage of span `span` of line `y` (1 to 8 consecutive pixels, or one stored
    /// span), if it exists.
    #[doc(hidden)]
    #[inline(always)]
    fn span_unit(rows: &[Row], d: Dims, n: usize, span: u32, y: u32) -> Option<&[Row]> {
        if Self::SPANS {
            return unit(rows, d.span_index(span, y)?, LANES * n);
        }
        let x = span.checked_mul(LANES_U32).filter(|&x| x < d.width && y < d.height)?;
        rows.get(pixels_from(d, n, x, y))
    }

    /// A span insert at `at` (checked before; its `x` any column): `F::insert` on each unit
    /// of storage it touches, with the lanes and the mask as they lie there. In spans, a
    /// span at `x` not a multiple of 8 touches two stored spans: lane `i` lands on lane
    /// `(i + x % 8) % 8`, of the first if `i + x % 8 < 8`, of the next one otherwise.
    #[doc(hidden)]
    #[inline(always)]
    #[expect(
        clippy::cast_possible_truncation,
        reason = "the two bytes of the mask shifted into 16 bits"
    )]
    fn insert_span<F: InsertUnit>(rows: &mut [Row], d: Dims, n: usize, at: SpanAt, span: SpanRows<'_>) {
        if !Self::SPANS {
            if let Some(px) = rows.get_mut(pixels_from(d, n, at.x, at.y)) {
                F::insert(px, span);
            }
            return;
        }
        let shift = at.x as usize % LANES;
        let wide = (span.mask as u16) << shift;
        let (m0, m1) = (wide as u8, (wide >> 8) as u8);
        let rotated;
        let (lanes, hashes) = if shift == 0 {
            (span.rows, span.hashes)
        } else {
            rotated = (rotate(span.rows, shift), rotate(span.hashes, shift));
            (&rotated.0, &rotated.1)
        };
        for (i, mask) in [(at.index, m0), (at.index + 1, m1)] {
            if mask != 0
                && let Some(s) = unit_mut(rows, i, LANES * n)
            {
                F::insert(
                    s,
                    SpanRows {
                        rows: lanes,
                        hashes,
                        mask,
                    },
                );
            }
        }
    }

    /// [`insert_span`](Self::insert_span) at a span whose `x` is a multiple of 8 (the
    /// batcher's flush): in spans, its one stored span without the rotation's branches (with
    /// them the batched inserts ran up to 1.17x the instructions, callgrind x86-64-v3).
    #[doc(hidden)]
    #[inline(always)]
    fn insert_aligned<F: InsertUnit>(rows: &mut [Row], d: Dims, n: usize, at: SpanAt, span: SpanRows<'_>) {
        if !Self::SPANS {
            Self::insert_span::<F>(rows, d, n, at, span);
        } else if let Some(s) = unit_mut(rows, at.index, LANES * n) {
            F::insert(s, span);
        }
    }

    /// Pixel `(x, y)` (checked before) as `H` head and `T` tail slots: the kind's
    /// `leaf.pixel` on its rows (borrowed pixel-major; gathered from its lane and written
    /// back in spans), or, in spans where `lane_pays`, `leaf.lane` on its stored span.
    #[doc(hidden)]
    #[inline(always)]
    fn pixel_mut<const H: usize, const T: usize>(
        rows: &mut [Row],
        d: Dims,
        x: u32,
        y: u32,
        lane_pays: bool,
        leaf: impl PixelLeaf<H, T>,
    ) {
        if !Self::SPANS {
            if let Some(px) = unit_mut(rows, d.index_unchecked(x, y), H + T)
                && let Some((h, t)) = px.split_first_chunk_mut::<H>()
                && let Some(t) = t.first_chunk_mut::<T>()
            {
                leaf.pixel(h, t);
            }
            return;
        }
        let at = d.span_at(x, y);
        let l = x as usize % LANES;
        let Some((head, tail)) = unit_mut(rows, at.index, LANES * (H + T)).and_then(split_span_mut::<H, T>) else {
            return;
        };
        if lane_pays {
            leaf.lane(head, tail, l);
        } else {
            let (mut h, mut t) = (lane_rows(head, l), lane_rows(tail, l));
            leaf.pixel(&mut h, &mut t);
            set_lane_rows(head, l, h);
            set_lane_rows(tail, l, t);
        }
    }

    /// `f` of the unit of one span as `H` head and `T` tail layers (lanes past pixel-major
    /// pixels: empty rows, and `fill` in the tail layers); `or()` if the unit is not one.
    /// (Not an `Option`: returned through one, the resolves ran up to 1.17x the instructions.)
    #[doc(hidden)]
    #[inline(always)]
    fn layers<const H: usize, const T: usize, R>(
        unit: &[Row],
        fill: Row,
        f: impl FnOnce(&Layers8<H>, &Layers8<T>) -> R,
        or: impl FnOnce() -> R,
    ) -> R {
        if Self::SPANS {
            return split_span::<H, T>(unit).map_or_else(or, |(h, t)| f(h, t));
        }
        let (head, tail) = gather::<H, T>(unit, fill);
        f(&head, &tail)
    }

    /// [`layers`](Self::layers), mutable, for a kind's `leaf`: a pixel-major unit's lanes
    /// set in `mask` are scattered back.
    #[doc(hidden)]
    #[inline(always)]
    fn layers_mut<const H: usize, const T: usize>(unit: &mut [Row], fill: Row, mask: u8, leaf: impl SpanLeaf<H, T>) {
        if Self::SPANS {
            if let Some((h, t)) = split_span_mut::<H, T>(unit) {
                leaf.span(h, t);
            }
            return;
        }
        let (mut head, mut tail) = gather::<H, T>(unit, fill);
        leaf.span(&mut head, &mut tail);
        scatter::<H, T>(unit, mask, &head, &tail);
    }

    /// `span(layers)` of the unit of one span of `N` layers, or `pixels(px)` where it is 8
    /// whole pixel-major pixels (a kind's pixel-major cell, read without the transpose).
    #[doc(hidden)]
    #[inline(always)]
    fn layers_or_pixels<const N: usize, R>(
        unit: &[Row],
        span: impl FnOnce(&Layers8<N>) -> R,
        pixels: impl FnOnce(&[[Row; N]; LANES]) -> R,
        or: impl FnOnce() -> R,
    ) -> R {
        if Self::SPANS {
            return as_layers::<N>(unit).map_or_else(or, span);
        }
        match unit.as_chunks::<N>().0.try_into() {
            Ok(px) => pixels(px),
            Err(_) => span(&gather::<N, 0>(unit, Row::EMPTY).0),
        }
    }

    /// The whole spans of a line (`N` slots per pixel), as stored spans (`spans`) or as
    /// groups of 8 pixel-major pixels (`pixels`).
    #[doc(hidden)]
    #[inline(always)]
    fn lines<const N: usize, O: ?Sized>(
        line: &[Row],
        out: &mut O,
        spans: impl FnOnce(&[Layers8<N>], &mut O),
        pixels: impl FnOnce(&[[[Row; N]; LANES]], &mut O),
    ) {
        if Self::SPANS {
            spans(line.as_chunks::<LANES>().0.as_chunks::<N>().0, out);
        } else {
            pixels(line.as_chunks::<N>().0.as_chunks::<LANES>().0, out);
        }
    }
}

impl Arrangement for PixelMajor {
    const SPANS: bool = false;
}

impl Arrangement for Spans {
    const SPANS: bool = true;
}

/// The pixel-major rows of the 1 to 8 pixels of a span from `(x, y)` (checked before), `n`
/// per pixel: the unit of that span.
#[inline(always)]
fn pixels_from(d: Dims, n: usize, x: u32, y: u32) -> core::ops::Range<usize> {
    let first = d.index_unchecked(x, y);
    first * n..(first + d.lanes_inside(x)) * n
}

/// Unit `i` of `n` rows.
#[inline(always)]
fn unit(rows: &[Row], i: usize, n: usize) -> Option<&[Row]> {
    rows.get(i * n..(i + 1) * n)
}

/// Unit `i` of `n` rows, mutable.
#[inline(always)]
fn unit_mut(rows: &mut [Row], i: usize, n: usize) -> Option<&mut [Row]> {
    rows.get_mut(i * n..(i + 1) * n)
}

/// The lanes of a span insert, rotated so that lane `i` sits at `(i + shift) % 8`.
fn rotate<T: Copy>(rows: &[T; LANES], shift: usize) -> [T; LANES] {
    let mut r = *rows;
    r.rotate_right(shift);
    r
}

/// `rows` as `N` layers of 8 rows, when it holds at least that (the rest ignored).
#[inline(always)]
fn as_layers<const N: usize>(rows: &[Row]) -> Option<&Layers8<N>> {
    rows.as_chunks::<LANES>().0.try_into().ok()
}

/// [`as_layers`], mutable.
#[inline(always)]
fn as_layers_mut<const N: usize>(rows: &mut [Row]) -> Option<&mut Layers8<N>> {
    rows.as_chunks_mut::<LANES>().0.try_into().ok()
}

/// The `H` head and `T` tail layers of a stored span.
#[inline(always)]
fn split_span<const H: usize, const T: usize>(span: &[Row]) -> Option<(&Layers8<H>, &Layers8<T>)> {
    let (head, tail) = span.split_at_checked(H * LANES)?;
    Some((as_layers::<H>(head)?, as_layers::<T>(tail)?))
}

/// [`split_span`], mutable.
#[inline(always)]
fn split_span_mut<const H: usize, const T: usize>(span: &mut [Row]) -> Option<(&mut Layers8<H>, &mut Layers8<T>)> {
    let (head, tail) = span.split_at_mut_checked(H * LANES)?;
    Some((as_layers_mut::<H>(head)?, as_layers_mut::<T>(tail)?))
}

/// Gather the 1 to 8 pixels of `px` (`H + T` slots each) into `H` head and `T` tail layers;
/// lanes past the pixels hold empty rows and `fill` in the tail layers.
#[inline(always)]
fn gather<const H: usize, const T: usize>(px: &[Row], fill: Row) -> (Layers8<H>, Layers8<T>) {
    let n = H + T;
    // A whole span (the common case): a transpose with constant indices, no fill first
    // (`get` cannot fail there; it keeps the code free of panics). HT's measured cell.
    if let Some(px) = px.get(..LANES * n) {
        let at = |lane: usize, slot: usize| px.get(lane * n + slot).copied().unwrap_or(fill);
        let head = core::array::from_fn(|layer| core::array::from_fn(|lane| at(lane, layer)));
        let tail = core::array::from_fn(|layer| core::array::from_fn(|lane| at(lane, H + layer)));
        return (head, tail);
    }
    let mut head = [[Row::EMPTY; LANES]; H];
    let mut tail = [[fill; LANES]; T];
    // One pass over the pixels' slots (contiguous): head rows, then the tail slots.
    for (lane, p) in px.chunks_exact(n).take(LANES).enumerate() {
        let (h, t) = p.split_at(H.min(p.len()));
        for (layer, row) in head.iter_mut().zip(h) {
            layer[lane] = *row;
        }
        for (layer, row) in tail.iter_mut().zip(t) {
            layer[lane] = *row;
        }
    }
    (head, tail)
}

/// The inverse of [`gather`] for the lanes set in `mask`.
#[inline(always)]
fn scatter<const H: usize, const T: usize>(px: &mut [Row], mask: u8, head: &Layers8<H>, tail: &Layers8<T>) {
    for (lane, p) in px.chunks_exact_mut(H + T).take(LANES).enumerate() {
        if mask & (1 << lane) == 0 {
            continue;
        }
        let (h, t) = p.split_at_mut(H.min(p.len()));
        for (layer, row) in head.iter().zip(h) {
            *row = layer[lane];
        }
        for (layer, row) in tail.iter().zip(t) {
            *row = layer[lane];
        }
    }
}

/// The rows of one lane of `N` layers (one pixel of a span), gathered into an array, for a
/// pixel insert in scalar code on span storage ([`set_lane_rows`] writes them back). Two functions,
/// not one taking a closure: a closure is a call where the caller is large
/// (`DynFramebuffer`'s match over every size).
#[inline(always)]
pub(crate) fn lane_rows<const N: usize>(layers: &Layers8<N>, lane: usize) -> [Row; N] {
    core::array::from_fn(|j| layers[j].get(lane).copied().unwrap_or(Row::EMPTY))
}

/// Write back what [`lane_rows`] read.
#[inline(always)]
pub(crate) fn set_lane_rows<const N: usize>(layers: &mut Layers8<N>, lane: usize, px: [Row; N]) {
    for (layer, r) in layers.iter_mut().zip(px) {
        if let Some(slot) = layer.get_mut(lane) {
            *slot = r;
        }
    }
}
