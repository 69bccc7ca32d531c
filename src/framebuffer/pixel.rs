//! What a pixel holds: [`Mlab`] (`M` rows) or [`Ht`] (`K` head rows and a tail), each in an
//! arithmetic. The only code of the storage layer that names `M`, `K` or the tail type: every
//! per-kind leaf is here, over layer-major spans (`M` layers; `K` head layers and the tails)
//! or one pixel's rows that the arrangement ([`PixelMajor`](super::PixelMajor),
//! [`Spans`](super::Spans)) hands it, borrowed or gathered: no leaf asks which arrangement
//! it runs on. The measured pixel-major cells are named as such: MLAB's resolve of 8 whole
//! pixel-major pixels without the transpose, MLAB's one-lane insert with AVX, HT's
//! span-insert facts.

use core::fmt::Debug;
use core::marker::PhantomData;

use super::arrangement::{Arrangement, Layers8, PixelLeaf, SpanLeaf, SpanRows, lane_rows, set_lane_rows};
use super::dims::Dims;
use super::{CLEAR_LANES, Layers};
use crate::arith::{Arithmetic, Unbiased};
use crate::hybrid::{self, TailFormat};
use crate::lanes::{self, LANES, ResolvedLanes};
use crate::mlab;
use crate::resolve::int::IntBackground;
use crate::resolve::{Background, Resolved, resolve_rows};
use crate::row::Row;

impl<const M: usize, A: Arithmetic> crate::sealed::Sealed for Mlab<M, A> {}
impl<const K: usize, A: Arithmetic> crate::sealed::Sealed for Ht<K, A> {}

/// MLAB with `M` rows per pixel in the arithmetic `A`: a [`Pixel`] kind of a
/// [`Grid`](super::Grid).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct Mlab<const M: usize, A: Arithmetic = Unbiased>(PhantomData<A>);

/// Hybrid Transparency with `K` head rows and one tail (`K + 1` row-sized slots per pixel)
/// in the arithmetic `A`, which picks the tail format: a [`Pixel`] kind of a
/// [`Grid`](super::Grid).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct Ht<const K: usize, A: Arithmetic = Unbiased>(PhantomData<A>);

/// What one pixel of a [`Grid`](super::Grid) holds: [`Mlab`] or [`Ht`] (sealed). The
/// hidden items are the storage layer's leaves.
// `Dims` is the crate's own: the trait is sealed, no other crate implements or calls it.
#[allow(private_interfaces)]
pub trait Pixel: crate::sealed::Sealed + Copy + Debug + Send + Sync + 'static {
    /// The arithmetic of the merge, of quantization and of the tail.
    type Arith: Arithmetic;
    /// One pixel's contents, as [`Grid::pixel`](super::Grid::pixel) returns them:
    /// `[Row; M]`, or `([Row; K], tail)`.
    type Value: Copy + Debug + PartialEq;
    /// Row-sized (8-byte) slots per pixel: `M`, or `K + 1`.
    const ROWS: usize;
    /// The method and size.
    const LAYERS: Layers;
    /// Whether span inserts into pixel-major storage beat pixel inserts (measured,
    /// `docs/performance.md`): not for HT, whose gather/insert/scatter has no merge to share.
    #[doc(hidden)]
    const PIXEL_MAJOR_SPAN_INSERTS_PAY: bool;
    /// Whether its insert merges rows (MLAB), which reads the fragments' hashes; HT's
    /// inserts of quantized rows do not.
    #[doc(hidden)]
    const MERGES: bool;

    /// Resolve one pixel (Eq. 5, or head and tail).
    fn resolve(value: &Self::Value) -> Resolved;
    /// Whether the pixel's HT tail has a field at its maximum (never for MLAB).
    fn saturated(value: &Self::Value) -> bool;

    /// The value from its slots (`slot(j)` for `j` in `0..ROWS`; HT: the tail's bytes last).
    #[doc(hidden)]
    fn from_slots(slot: impl Fn(usize) -> Row) -> Self::Value;
    /// The slots of a value, in order.
    #[doc(hidden)]
    fn to_slots(value: Self::Value, put: impl FnMut(usize, Row));
    /// Slot `j` of an empty pixel.
    #[doc(hidden)]
    fn empty_slot(j: usize) -> Row;
    /// Listing 1 or 2 on pixel `(x, y)` (checked before) of `rows` in the arrangement `L`.
    #[doc(hidden)]
    fn insert_pixel<L: Arrangement>(rows: &mut [Row], d: Dims, x: u32, y: u32, row: Row, h: u32);
    /// A span insert, for the lanes set in `mask`, into the storage `unit` of one span in the
    /// arrangement `L`: a stored span, or 1 to 8 consecutive pixel-major pixels (the lanes
    /// past them are off).
    #[doc(hidden)]
    fn insert_span<L: Arrangement>(unit: &mut [Row], span: SpanRows<'_>);
    /// The f32 resolve of the storage of one span (as for `insert_span`), lanes past its
    /// pixels clear.
    #[doc(hidden)]
    fn resolve_f32<L: Arrangement>(unit: &[Row]) -> ResolvedLanes;
    /// The integer (RGBA8) resolve of the storage of one span.
    #[doc(hidden)]
    fn resolve_int<L: Arrangement>(unit: &[Row], background: IntBackground) -> [[u8; 4]; LANES];
    /// [`resolve_int`](Self::resolve_int) of the whole spans of one line (`line`: the line's
    /// rows), into `out`.
    #[doc(hidden)]
    fn resolve_line_int<L: Arrangement>(line: &[Row], out: &mut [[[u8; 4]; LANES]], background: IntBackground);
    /// The integer resolve of 8 empty pixels (a span that does not exist), as this kind's
    /// integer resolve writes an empty pixel: for a background that is not a byte value it
    /// may differ from [`crate::to_rgba8`] of it by one step.
    #[doc(hidden)]
    fn clear_int(background: Background) -> [[u8; 4]; LANES];
}

/// MLAB's insert of one row: Listing 1 on one pixel's rows, or on its lane of a stored span.
#[derive(Clone, Copy)]
struct MlabRow<A, const M: usize>(Row, u32, PhantomData<A>);

impl<A: Arithmetic, const M: usize> PixelLeaf<M, 0> for MlabRow<A, M> {
    #[inline(always)]
    fn pixel(self, px: &mut [Row; M], _: &mut [Row; 0]) {
        mlab::insert_hashed::<A, M>(px, self.0, self.1);
    }

    /// MLAB's one-lane cell (see [`MLAB_LANE_INSERT_PAYS`]).
    #[inline(always)]
    fn lane(self, span: &mut Layers8<M>, _: &mut Layers8<0>, lane: usize) {
        lanes::mlab_insert_hashed::<A, M>(span, &[self.0; LANES], &[self.1; LANES], 1 << (lane % LANES));
    }
}

/// MLAB's span insert: Listing 1 in lanes, for the lanes that are on.
struct MlabSpan<'r, A, const M: usize>(SpanRows<'r>, PhantomData<A>);

impl<A: Arithmetic, const M: usize> SpanLeaf<M, 0> for MlabSpan<'_, A, M> {
    #[inline(always)]
    fn span(self, span: &mut Layers8<M>, _: &mut Layers8<0>) {
        let SpanRows { rows, hashes, mask } = self.0;
        lanes::mlab_insert_hashed::<A, M>(span, rows, hashes, mask);
    }
}

/// HT's insert of one row: Listing 2 in scalar code on one pixel's head rows and tail slot,
/// or on its lane of a stored span, its head rows gathered and the tail in place (one pixel
/// does not pay for eight lanes, `docs/performance.md`; the tail gathered as well: 1.035x
/// the instructions).
#[derive(Clone, Copy)]
struct HtRow<A, const K: usize>(Row, PhantomData<A>);

impl<A: Arithmetic, const K: usize> PixelLeaf<K, 1> for HtRow<A, K> {
    #[inline(always)]
    fn pixel(self, head: &mut [Row; K], [t]: &mut [Row; 1]) {
        let mut tail = A::Tail::from_bytes(t.to_bytes());
        hybrid::insert(head, &mut tail, self.0);
        *t = Row::from_bytes(tail.to_bytes());
    }

    #[inline(always)]
    fn lane(self, head: &mut Layers8<K>, [tails]: &mut Layers8<1>, lane: usize) {
        let tails = bytemuck::cast_mut::<_, [A::Tail; LANES]>(tails);
        if let Some(tail) = tails.get_mut(lane) {
            let mut px = lane_rows(head, lane);
            hybrid::insert(&mut px, tail, self.0);
            set_lane_rows(head, lane, px);
        }
    }
}

/// HT's span insert: Listing 2 in lanes on the head layers and tails, for the lanes that are
/// on (the hashes unread).
struct HtSpan<'r, A, const K: usize>(SpanRows<'r>, PhantomData<A>);

impl<A: Arithmetic, const K: usize> SpanLeaf<K, 1> for HtSpan<'_, A, K> {
    #[inline(always)]
    fn span(self, head: &mut Layers8<K>, [tails]: &mut Layers8<1>) {
        let tails = bytemuck::cast_mut::<_, [A::Tail; LANES]>(tails);
        lanes::hybrid_insert_parts(head, tails, self.0.rows, self.0.mask);
    }
}

/// MLAB's measured cell for a pixel insert into span storage: with AVX, a span insert of one
/// lane; without, the pixel's rows gathered, Listing 1 in scalar code, written back (the
/// faster of the two on each, `docs/performance.md`). The same rows either way.
const MLAB_LANE_INSERT_PAYS: bool = cfg!(target_feature = "avx");

#[allow(private_interfaces)]
impl<const M: usize, A: Arithmetic> Pixel for Mlab<M, A> {
    type Arith = A;
    type Value = [Row; M];
    const ROWS: usize = {
        let () = mlab::AtLeastOne::<M>::OK;
        M
    };
    const LAYERS: Layers = Layers::Mlab(M);
    const PIXEL_MAJOR_SPAN_INSERTS_PAY: bool = true;
    const MERGES: bool = true;

    fn resolve(value: &[Row; M]) -> Resolved {
        resolve_rows(value)
    }

    fn saturated(_: &[Row; M]) -> bool {
        false
    }

    fn from_slots(slot: impl Fn(usize) -> Row) -> [Row; M] {
        core::array::from_fn(slot)
    }

    fn to_slots(value: [Row; M], mut put: impl FnMut(usize, Row)) {
        value.into_iter().enumerate().for_each(|(j, r)| put(j, r));
    }

    fn empty_slot(_: usize) -> Row {
        Row::EMPTY
    }

    #[inline(always)] // also in each arm of DynFramebuffer's match (a call there: 1.2x)
    fn insert_pixel<L: Arrangement>(rows: &mut [Row], d: Dims, x: u32, y: u32, row: Row, h: u32) {
        let leaf = MlabRow::<A, M>(row, h, PhantomData);
        L::pixel_mut::<M, 0>(rows, d, x, y, MLAB_LANE_INSERT_PAYS, leaf);
    }

    #[inline(always)]
    fn insert_span<L: Arrangement>(unit: &mut [Row], span: SpanRows<'_>) {
        L::layers_mut::<M, 0>(unit, Row::EMPTY, span.mask, MlabSpan::<A, M>(span, PhantomData));
    }

    /// 8 whole pixel-major pixels: MLAB's pixel-major cell, without the transpose.
    #[inline(always)]
    fn resolve_f32<L: Arrangement>(unit: &[Row]) -> ResolvedLanes {
        L::layers_or_pixels::<M, _>(unit, lanes::mlab_resolve, lanes::mlab_resolve_pixel_major, || {
            CLEAR_LANES
        })
    }

    /// 8 whole pixel-major pixels: MLAB's pixel-major cell, without the transpose.
    #[inline(always)]
    fn resolve_int<L: Arrangement>(unit: &[Row], bg: IntBackground) -> [[u8; 4]; LANES] {
        let span = |l: &Layers8<M>| lanes::mlab_resolve_rgba8(l, bg);
        let whole = |px: &[[Row; M]; LANES]| lanes::mlab_resolve_rgba8(lanes::PixelCell(px), bg);
        L::layers_or_pixels::<M, _>(unit, span, whole, || span(&[[Row::EMPTY; LANES]; M]))
    }

    /// The pixel-major line: MLAB's pixel-major cell, the pixels cast to `[[Row; M]; 8]` once
    /// per line.
    #[inline(always)]
    fn resolve_line_int<L: Arrangement>(line: &[Row], out: &mut [[[u8; 4]; LANES]], bg: IntBackground) {
        L::lines::<M, _>(
            line,
            out,
            |spans, out| lanes::mlab_resolve_line_rgba8(spans.iter(), out, bg),
            |pixels, out| lanes::mlab_resolve_line_rgba8(pixels.iter().map(lanes::PixelCell), out, bg),
        );
    }

    /// An empty pixel's integer resolve (its `M` empty rows).
    fn clear_int(background: Background) -> [[u8; 4]; LANES] {
        [crate::resolve::int::rgba8(&[Row::EMPTY; M], background); LANES]
    }
}

/// How many spans HT's RGBA8 line loop resolves at once: four with AVX2 (two 256-bit
/// chains), two without (SSE2: two 128-bit chains; four spilled, 1.14x the time).
const HT_RESOLVE_GROUP: usize = if cfg!(target_feature = "avx2") { 4 } else { 2 };

impl<const K: usize, A: Arithmetic> Ht<K, A> {
    /// The bytes of an empty tail in a row-sized slot.
    #[inline(always)]
    fn empty_tail() -> Row {
        Row::from_bytes(A::Tail::EMPTY.to_bytes())
    }

    /// `f(head, tails)` of the storage of one span in the arrangement `L` (pixel-major pixels
    /// gathered, empty rows and tails past them).
    #[inline(always)]
    fn view<L: Arrangement, R>(unit: &[Row], f: impl FnOnce(&Layers8<K>, &[A::Tail; LANES]) -> R) -> Option<R> {
        L::layers::<K, 1, _>(
            unit,
            Self::empty_tail(),
            |h, [t]| Some(f(h, bytemuck::cast_ref(t))),
            || None,
        )
    }

    /// [`view`](Self::view), `or()` where the unit is not a span.
    #[inline(always)]
    fn view_or<L: Arrangement, R>(
        unit: &[Row],
        f: impl FnOnce(&Layers8<K>, &[A::Tail; LANES]) -> R,
        or: impl FnOnce() -> R,
    ) -> R {
        L::layers::<K, 1, _>(unit, Self::empty_tail(), |h, [t]| f(h, bytemuck::cast_ref(t)), or)
    }

    /// Whether every tail slot of the storage of one span in the arrangement `L` is empty
    /// (all bits zero; slots past the storage count as empty).
    #[inline(always)]
    fn tails_empty<L: Arrangement>(unit: &[Row]) -> bool {
        let word = |lane: usize| {
            unit.get(L::unit_slot(K + 1, lane, K))
                .map_or(0, |r| bytemuck::cast::<Row, u64>(*r))
        };
        (0..LANES).fold(0, |a, lane| a | word(lane)) == 0
    }

    /// The integer resolve of the spans `i0`, `i1` of a line (`at(i)`: the unit of span `i`),
    /// their tails' dependency chains overlapped.
    #[inline(always)]
    fn resolve_pair<'l, L: Arrangement>(
        at: impl Fn(usize) -> &'l [Row],
        [i0, i1]: [usize; 2],
        bg: IntBackground,
    ) -> Option<[[[u8; 4]; LANES]; 2]> {
        Self::view::<L, _>(at(i0), |h0, t0| {
            Self::view::<L, _>(at(i1), |h1, t1| {
                lanes::hybrid_resolve_parts2_rgba8([(h0, t0), (h1, t1)], bg)
            })
        })
        .flatten()
    }

    /// [`resolve_pair`](Self::resolve_pair) of four spans.
    #[inline(always)]
    fn resolve_four<'l, L: Arrangement>(
        at: impl Fn(usize) -> &'l [Row],
        [i0, i1, i2, i3]: [usize; 4],
        bg: IntBackground,
    ) -> Option<[[[u8; 4]; LANES]; 4]> {
        Self::view::<L, _>(at(i0), |h0, t0| {
            Self::view::<L, _>(at(i1), |h1, t1| {
                Self::view::<L, _>(at(i2), |h2, t2| {
                    Self::view::<L, _>(at(i3), |h3, t3| {
                        lanes::hybrid_resolve_parts4_rgba8([(h0, t0), (h1, t1), (h2, t2), (h3, t3)], bg)
                    })
                })
            })
        })
        .flatten()
        .flatten()
        .flatten()
    }
}

#[allow(private_interfaces)]
impl<const K: usize, A: Arithmetic> Pixel for Ht<K, A> {
    type Arith = A;
    type Value = ([Row; K], A::Tail);
    const ROWS: usize = K + 1;
    const LAYERS: Layers = Layers::Hybrid(K);
    const PIXEL_MAJOR_SPAN_INSERTS_PAY: bool = false;
    const MERGES: bool = false;

    fn resolve(value: &Self::Value) -> Resolved {
        hybrid::resolve(&value.0, value.1)
    }

    fn saturated(value: &Self::Value) -> bool {
        value.1.saturated()
    }

    fn from_slots(slot: impl Fn(usize) -> Row) -> Self::Value {
        (core::array::from_fn(&slot), A::Tail::from_bytes(slot(K).to_bytes()))
    }

    fn to_slots((head, tail): Self::Value, mut put: impl FnMut(usize, Row)) {
        head.into_iter().enumerate().for_each(|(j, r)| put(j, r));
        put(K, Row::from_bytes(tail.to_bytes()));
    }

    fn empty_slot(j: usize) -> Row {
        if j < K { Row::EMPTY } else { Self::empty_tail() }
    }

    /// The pixel's head rows and tail (gathered from their lane in span storage), Listing 2
    /// in scalar code: one pixel does not pay for eight lanes (`docs/performance.md`).
    #[inline(always)] // also in each arm of DynFramebuffer's match (a call there: 1.2x)
    fn insert_pixel<L: Arrangement>(rows: &mut [Row], d: Dims, x: u32, y: u32, row: Row, _: u32) {
        L::pixel_mut::<K, 1>(rows, d, x, y, true, HtRow::<A, K>(row, PhantomData));
    }

    #[inline(always)]
    fn insert_span<L: Arrangement>(unit: &mut [Row], span: SpanRows<'_>) {
        L::layers_mut::<K, 1>(unit, Self::empty_tail(), span.mask, HtSpan::<A, K>(span, PhantomData));
    }

    #[inline(always)]
    #[expect(
        clippy::redundant_closure,
        reason = "measured as a closure; the function as a value is called through its FnOnce shim"
    )]
    fn resolve_f32<L: Arrangement>(unit: &[Row]) -> ResolvedLanes {
        Self::view_or::<L, _>(unit, |h, t| lanes::hybrid_resolve_parts(h, t), || CLEAR_LANES)
    }

    #[inline(always)]
    fn resolve_int<L: Arrangement>(unit: &[Row], bg: IntBackground) -> [[u8; 4]; LANES] {
        let f = |h: &Layers8<K>, t: &[A::Tail; LANES]| lanes::hybrid_resolve_parts_rgba8(h, t, bg);
        Self::view_or::<L, _>(unit, f, || f(&[[Row::EMPTY; LANES]; K], &[A::Tail::EMPTY; LANES]))
    }

    /// Spans whose tails are all empty alone (their heads' resolve), the others in groups of
    /// [`HT_RESOLVE_GROUP`] (`lanes::hybrid_resolve_parts{2,4}_rgba8`: the tails' dependency
    /// chains of the group's spans overlap), the last ones two at a time and alone.
    #[inline(always)]
    fn resolve_line_int<L: Arrangement>(line: &[Row], out: &mut [[[u8; 4]; LANES]], bg: IntBackground) {
        let unit = LANES * Self::ROWS;
        let at = |i: usize| line.get(i * unit..(i + 1) * unit).unwrap_or(&[]);
        let mut put = |j: usize, r: Option<[[u8; 4]; LANES]>| {
            if let Some(o) = out.get_mut(j) {
                *o = r.unwrap_or_else(|| Self::resolve_int::<L>(at(j), bg));
            }
        };
        let mut group = [0usize; 4];
        let mut len = 0;
        for (i, u) in line.chunks_exact(unit).enumerate() {
            if Self::tails_empty::<L>(u) {
                put(i, Self::view::<L, _>(u, |h, _| lanes::hybrid_resolve_head_rgba8(h, bg)));
                continue;
            }
            if let Some(g) = group.get_mut(len) {
                *g = i;
            }
            len += 1;
            if len < HT_RESOLVE_GROUP {
                continue;
            }
            len = 0;
            if HT_RESOLVE_GROUP == 2 {
                let two = Self::resolve_pair::<L>(at, [group[0], group[1]], bg);
                put(group[0], two.map(|r| r[0]));
                put(group[1], two.map(|r| r[1]));
                continue;
            }
            let four = Self::resolve_four::<L>(at, group, bg);
            for (k, j) in group.into_iter().enumerate() {
                put(j, four.map(|r| r[k & 3]));
            }
        }
        let rest = group.get(..len).unwrap_or(&[]);
        let mut pairs = rest.chunks_exact(2);
        for p in &mut pairs {
            if let [i0, i1] = *p {
                let two = Self::resolve_pair::<L>(at, [i0, i1], bg);
                put(i0, two.map(|r| r[0]));
                put(i1, two.map(|r| r[1]));
            }
        }
        for &j in pairs.remainder() {
            put(j, None);
        }
    }

    /// An empty pixel's integer resolve (empty head rows, empty tail: as MLAB's, an empty
    /// tail adds nothing).
    fn clear_int(background: Background) -> [[u8; 4]; LANES] {
        [crate::resolve::int::ht_rgba8(&[Row::EMPTY; K], A::Tail::EMPTY, background); LANES]
    }
}
