//! What a pixel holds: [`Mlab`] (`M` rows) or [`Ht`] (`K` head rows and a tail), each in an
//! arithmetic. The only code of the storage layer that names `M`, `K` or the tail type: every
//! per-kind fast path is a leaf here, called by the two arrangements
//! ([`PixelMajor`](super::PixelMajor), [`Spans`](super::Spans)) with the rows of one unit of
//! storage:
//!
//! - pixel-major leaves (`pm_*`) get one pixel's rows, or the rows of 1 to 8 consecutive
//!   pixels of a line (a span; fewer than 8 at the right edge);
//! - span leaves (`span_*`) get one stored 8-pixel span, layer-major (`8 * ROWS` rows).

use core::fmt::Debug;
use core::marker::PhantomData;

use super::{Arrangement, CLEAR_LANES, Layers};
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
    /// Whether the pixel-major RGBA8 resolve walks whole spans in the line loop (see the
    /// HT implementation for where it does not).
    #[doc(hidden)]
    const PIXEL_MAJOR_LINE_LOOP: bool = true;

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
    /// Listing 1 or 2 on one pixel-major pixel (`px`: its `ROWS` slots).
    #[doc(hidden)]
    fn pm_insert(px: &mut [Row], row: Row, h: u32);
    /// Listing 1 or 2 on lane `lane` of a stored span (`8 * ROWS` rows, layer-major).
    #[doc(hidden)]
    fn span_insert(span: &mut [Row], lane: usize, row: Row, h: u32);
    /// A span insert, for the lanes set in `mask`, into the storage `unit` of one span in the
    /// arrangement `L`: a stored span, or 1 to 8 consecutive pixel-major pixels (the lanes
    /// past them are off).
    #[doc(hidden)]
    fn insert_unit<L: Arrangement>(unit: &mut [Row], rows: &[Row; LANES], hashes: &[u32; LANES], mask: u8);
    /// The f32 resolve of the storage of one span (as for `insert_unit`), lanes past its
    /// pixels clear.
    #[doc(hidden)]
    fn resolve_unit<L: Arrangement>(unit: &[Row]) -> ResolvedLanes;
    /// The RGBA8 resolve of the storage of one span, as this kind writes RGBA8.
    #[doc(hidden)]
    fn resolve_unit_rgba8<L: Arrangement>(unit: &[Row], background: IntBackground) -> [[u8; 4]; LANES];
    /// [`resolve_unit_rgba8`](Self::resolve_unit_rgba8) of the whole spans of one line
    /// (`line`: the line's rows), into `out`.
    #[doc(hidden)]
    #[inline(always)]
    fn resolve_line_rgba8<L: Arrangement>(line: &[Row], out: &mut [[[u8; 4]; LANES]], background: IntBackground) {
        for (o, u) in out.iter_mut().zip(line.chunks_exact(LANES * Self::ROWS)) {
            *o = Self::resolve_unit_rgba8::<L>(u, background);
        }
    }
    /// The RGBA8 of 8 empty pixels (a span that does not exist), as this kind's RGBA8
    /// resolve writes an empty pixel.
    #[doc(hidden)]
    fn clear_rgba8(background: Background) -> [[u8; 4]; LANES];
}

/// Gather rows `offset..offset + N` of each pixel of `px` (`stride` rows per pixel, at most
/// 8 pixels) into a layer-major span; lanes past the pixels hold `fill`.
#[inline(always)]
fn gather<const N: usize>(px: &[Row], stride: usize, offset: usize, fill: Row) -> [[Row; LANES]; N] {
    let mut span = [[fill; LANES]; N];
    for (lane, p) in px.chunks_exact(stride).take(LANES).enumerate() {
        if let Some(p) = p.get(offset..offset + N) {
            for (layer, row) in span.iter_mut().zip(p) {
                layer[lane] = *row;
            }
        }
    }
    span
}

/// The inverse of [`gather`] for the lanes set in `mask`.
#[inline(always)]
fn scatter<const N: usize>(px: &mut [Row], stride: usize, offset: usize, mask: u8, span: &[[Row; LANES]; N]) {
    for (lane, p) in px.chunks_exact_mut(stride).take(LANES).enumerate() {
        if mask & (1 << lane) == 0 {
            continue;
        }
        if let Some(p) = p.get_mut(offset..offset + N) {
            for (layer, row) in span.iter().zip(p) {
                *row = layer[lane];
            }
        }
    }
}

/// The rows of one lane of `N` layers (one pixel of a span), gathered into an array, for a
/// pixel insert in scalar code on span storage ([`set_lane_rows`] writes them back). Two functions,
/// not one taking a closure: a closure is a call where the caller is large
/// (`DynFramebuffer`'s match over every size).
#[inline(always)]
fn lane_rows<const N: usize>(layers: &[[Row; LANES]; N], lane: usize) -> [Row; N] {
    core::array::from_fn(|j| layers[j].get(lane).copied().unwrap_or(Row::EMPTY))
}

/// Write back what [`lane_rows`] read.
#[inline(always)]
fn set_lane_rows<const N: usize>(layers: &mut [[Row; LANES]; N], lane: usize, px: [Row; N]) {
    for (layer, r) in layers.iter_mut().zip(px) {
        if let Some(slot) = layer.get_mut(lane) {
            *slot = r;
        }
    }
}

/// `rows` as `N` layers of 8 rows (a stored span's layers), when it holds exactly that.
#[inline(always)]
fn layers<const N: usize>(rows: &[Row]) -> Option<&[[Row; LANES]; N]> {
    rows.as_chunks::<LANES>().0.try_into().ok()
}

/// [`layers`], mutable.
#[inline(always)]
fn layers_mut<const N: usize>(rows: &mut [Row]) -> Option<&mut [[Row; LANES]; N]> {
    rows.as_chunks_mut::<LANES>().0.try_into().ok()
}

impl<const M: usize, A: Arithmetic> Mlab<M, A> {
    /// `span(layers)` of the storage of one span in the arrangement `L` (pixel-major pixels
    /// gathered into layers, empty rows past them), or `whole(pixels)` of 8 whole
    /// pixel-major pixels, which a resolve reads without the transpose.
    #[inline(always)]
    fn view<L: Arrangement, R>(
        unit: &[Row],
        span: impl FnOnce(&[[Row; LANES]; M]) -> R,
        whole: impl FnOnce(&[[Row; M]; LANES]) -> R,
    ) -> Option<R> {
        if L::SPANS {
            return layers::<M>(unit).map(span);
        }
        Some(match unit.as_chunks::<M>().0.try_into() {
            Ok(px) => whole(px),
            Err(_) => span(&gather::<M>(unit, M, 0, Row::EMPTY)),
        })
    }
}

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

    #[inline(always)]
    fn pm_insert(px: &mut [Row], row: Row, h: u32) {
        if let Some(p) = px.first_chunk_mut::<M>() {
            mlab::insert_hashed::<A, M>(p, row, h);
        }
    }

    /// With AVX, a span insert of one lane; without, the pixel's rows gathered, Listing 1 in
    /// scalar code, scattered back (the faster of the two on each, `docs/performance.md`).
    /// The same rows either way.
    #[inline(always)] // also in each arm of DynFramebuffer's match (a call there: 1.2x)
    fn span_insert(span: &mut [Row], lane: usize, row: Row, h: u32) {
        if let Some(l) = layers_mut::<M>(span) {
            if cfg!(target_feature = "avx") {
                lanes::mlab_insert_hashed::<A, M>(l, &[row; LANES], &[h; LANES], 1 << (lane % LANES));
            } else {
                let mut px = lane_rows(l, lane);
                mlab::insert_hashed::<A, M>(&mut px, row, h);
                set_lane_rows(l, lane, px);
            }
        }
    }

    /// Pixel-major: the pixels gathered into a layer-major span, inserted in lanes, the
    /// lanes that are on scattered back.
    #[inline(always)]
    fn insert_unit<L: Arrangement>(unit: &mut [Row], rows: &[Row; LANES], hashes: &[u32; LANES], mask: u8) {
        if !L::SPANS {
            let mut span = gather::<M>(unit, M, 0, Row::EMPTY);
            lanes::mlab_insert_hashed::<A, M>(&mut span, rows, hashes, mask);
            scatter::<M>(unit, M, 0, mask, &span);
        } else if let Some(l) = layers_mut::<M>(unit) {
            lanes::mlab_insert_hashed::<A, M>(l, rows, hashes, mask);
        }
    }

    #[inline(always)]
    fn resolve_unit<L: Arrangement>(unit: &[Row]) -> ResolvedLanes {
        // Not through `view`: through it, MLAB M = 8 spans ran 1.17x the instructions (callgrind,
        // x86-64-v3; the same at M <= 4).
        if L::SPANS {
            return layers::<M>(unit).map_or(CLEAR_LANES, lanes::mlab_resolve);
        }
        match unit.as_chunks::<M>().0.try_into() {
            Ok(px) => lanes::mlab_resolve_pixel_major(px),
            Err(_) => lanes::mlab_resolve(&gather::<M>(unit, M, 0, Row::EMPTY)),
        }
    }

    #[inline(always)]
    fn resolve_unit_rgba8<L: Arrangement>(unit: &[Row], bg: IntBackground) -> [[u8; 4]; LANES] {
        let span = |l: &[[Row; LANES]; M]| lanes::mlab_resolve_rgba8(l, bg);
        let whole = |px: &[[Row; M]; LANES]| lanes::mlab_resolve_pixel_major_rgba8(px, bg);
        Self::view::<L, _>(unit, span, whole).unwrap_or_else(|| span(&[[Row::EMPTY; LANES]; M]))
    }

    #[inline(always)]
    fn resolve_line_rgba8<L: Arrangement>(line: &[Row], out: &mut [[[u8; 4]; LANES]], bg: IntBackground) {
        if L::SPANS {
            lanes::mlab_resolve_line_rgba8(line.as_chunks::<LANES>().0.as_chunks::<M>().0, out, bg);
        } else {
            lanes::mlab_resolve_pixel_major_line_rgba8(line.as_chunks::<M>().0.as_chunks::<LANES>().0, out, bg);
        }
    }

    /// The integer resolve of an empty pixel (`resolve::int`), which for a background that
    /// is not a byte value may differ from [`crate::to_rgba8`] of it by one step.
    /// An empty pixel's integer resolve (its `M` empty rows: a span outside writes what an
    /// empty pixel does).
    fn clear_rgba8(background: Background) -> [[u8; 4]; LANES] {
        [crate::resolve::int::rgba8(&[Row::EMPTY; M], background); LANES]
    }
}

/// How many spans HT's RGBA8 line loop resolves at once: four with AVX2 (two 256-bit
/// chains), two without (SSE2: two 128-bit chains; four spilled, 1.14x the time).
const HT_RESOLVE_GROUP: usize = if cfg!(target_feature = "avx2") { 4 } else { 2 };

/// Head layers and tails of a stored HT span.
type HtSpan<'s, const K: usize, T> = (&'s [[Row; LANES]; K], &'s [T; LANES]);
/// Head layers and tails of a stored HT span, mutable.
type HtSpanMut<'s, const K: usize, T> = (&'s mut [[Row; LANES]; K], &'s mut [T; LANES]);

impl<const K: usize, A: Arithmetic> Ht<K, A> {
    /// The bytes of an empty tail in a row-sized slot.
    #[inline(always)]
    fn empty_tail() -> Row {
        Row::from_bytes(A::Tail::EMPTY.to_bytes())
    }

    /// Head layers and tails of the 1 to 8 pixels of `px` (`K + 1` slots each); lanes past
    /// them hold empty rows and empty tails.
    #[inline(always)]
    fn gather(px: &[Row]) -> ([[Row; LANES]; K], [A::Tail; LANES]) {
        // A whole span (the common case): a transpose with constant indices, no fill first
        // (`get` cannot fail there; it keeps the code free of panics).
        if let Some(px) = px.get(..LANES * (K + 1)) {
            let at = |lane: usize, slot: usize| px.get(lane * (K + 1) + slot).copied().unwrap_or(Self::empty_tail());
            let head = core::array::from_fn(|layer| core::array::from_fn(|lane| at(lane, layer)));
            let tails: [Row; LANES] = core::array::from_fn(|lane| at(lane, K));
            return (head, bytemuck::cast(tails));
        }
        let mut head = [[Row::EMPTY; LANES]; K];
        let mut tails = [Self::empty_tail(); LANES];
        // One pass over the pixels' slots (contiguous): head rows, then the tail slot.
        for (lane, p) in px.chunks_exact(K + 1).take(LANES).enumerate() {
            if let (Some((t, h)), Some(tail)) = (p.split_last(), tails.get_mut(lane)) {
                for (layer, row) in head.iter_mut().zip(h) {
                    layer[lane] = *row;
                }
                *tail = *t;
            }
        }
        (head, bytemuck::cast(tails))
    }

    /// `f(head, tails)` of the storage of one span in the arrangement `L` (pixel-major pixels
    /// gathered, empty rows and tails past them).
    #[inline(always)]
    fn view<L: Arrangement, R>(unit: &[Row], f: impl FnOnce(&[[Row; LANES]; K], &[A::Tail; LANES]) -> R) -> Option<R> {
        if L::SPANS {
            return Self::parts(unit).map(|(h, t)| f(h, t));
        }
        let (head, tails) = Self::gather(unit);
        Some(f(&head, &tails))
    }

    /// Whether every tail slot of the storage of one span in the arrangement `L` is empty
    /// (all bits zero; slots past the storage count as empty).
    #[inline(always)]
    fn tails_empty<L: Arrangement>(unit: &[Row]) -> bool {
        let slot = |lane: usize| if L::SPANS { K * LANES + lane } else { lane * (K + 1) + K };
        let word = |lane: usize| unit.get(slot(lane)).map_or(0, |r| bytemuck::cast::<Row, u64>(*r));
        (0..LANES).fold(0, |a, lane| a | word(lane)) == 0
    }

    /// Head layers and tails of a stored span.
    #[inline(always)]
    fn parts(span: &[Row]) -> Option<HtSpan<'_, K, A::Tail>> {
        let (head, tails) = span.split_at_checked(K * LANES)?;
        let tails: &[Row; LANES] = tails.try_into().ok()?;
        Some((layers::<K>(head)?, bytemuck::cast_ref(tails)))
    }

    /// [`parts`](Self::parts), mutable.
    #[inline(always)]
    fn parts_mut(span: &mut [Row]) -> Option<HtSpanMut<'_, K, A::Tail>> {
        let (head, tails) = span.split_at_mut_checked(K * LANES)?;
        let tails: &mut [Row; LANES] = tails.try_into().ok()?;
        Some((layers_mut::<K>(head)?, bytemuck::cast_mut(tails)))
    }
}

impl<const K: usize, A: Arithmetic> Pixel for Ht<K, A> {
    type Arith = A;
    type Value = ([Row; K], A::Tail);
    const ROWS: usize = K + 1;
    const LAYERS: Layers = Layers::Hybrid(K);
    const PIXEL_MAJOR_SPAN_INSERTS_PAY: bool = false;
    const MERGES: bool = false;
    /// Without AVX2 and above `K = 4` the resolve goes span by span: the whole-span loop took
    /// 11 % longer there (`docs/performance.md`).
    const PIXEL_MAJOR_LINE_LOOP: bool = K <= 4 || cfg!(target_feature = "avx2");

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

    #[inline(always)]
    fn pm_insert(px: &mut [Row], row: Row, _: u32) {
        if let Some((t, h)) = px.split_last_mut()
            && let Ok(head) = <&mut [Row; K]>::try_from(h)
        {
            let mut tail = A::Tail::from_bytes(t.to_bytes());
            hybrid::insert(head, &mut tail, row);
            *t = Row::from_bytes(tail.to_bytes());
        }
    }

    /// The pixel's head rows and tail gathered, Listing 2 in scalar code, scattered back:
    /// one pixel does not pay for eight lanes (`docs/performance.md`).
    #[inline(always)] // also in each arm of DynFramebuffer's match (a call there: 1.2x)
    fn span_insert(span: &mut [Row], lane: usize, row: Row, _: u32) {
        if let Some((head, tails)) = Self::parts_mut(span)
            && let Some(tail) = tails.get_mut(lane)
        {
            let mut px = lane_rows(head, lane);
            hybrid::insert(&mut px, tail, row);
            set_lane_rows(head, lane, px);
        }
    }

    /// Pixel-major: the pixels' heads and tails gathered, inserted in lanes, the lanes that
    /// are on scattered back.
    #[inline(always)]
    fn insert_unit<L: Arrangement>(unit: &mut [Row], rows: &[Row; LANES], _: &[u32; LANES], mask: u8) {
        if L::SPANS {
            if let Some((head, tails)) = Self::parts_mut(unit) {
                lanes::hybrid_insert_parts(head, tails, rows, mask);
            }
            return;
        }
        let (mut head, mut tails) = Self::gather(unit);
        lanes::hybrid_insert_parts(&mut head, &mut tails, rows, mask);
        scatter::<K>(unit, K + 1, 0, mask, &head);
        let tails: [Row; LANES] = bytemuck::cast(tails);
        scatter::<1>(unit, K + 1, K, mask, &[tails]);
    }

    #[inline(always)]
    fn resolve_unit<L: Arrangement>(unit: &[Row]) -> ResolvedLanes {
        if L::SPANS {
            return Self::parts(unit).map_or(CLEAR_LANES, |(h, t)| lanes::hybrid_resolve_parts(h, t));
        }
        let (head, tails) = Self::gather(unit);
        lanes::hybrid_resolve_parts(&head, &tails)
    }

    #[inline(always)]
    fn resolve_unit_rgba8<L: Arrangement>(unit: &[Row], bg: IntBackground) -> [[u8; 4]; LANES] {
        let f = |h: &[[Row; LANES]; K], t: &[A::Tail; LANES]| lanes::hybrid_resolve_parts_rgba8(h, t, bg);
        Self::view::<L, _>(unit, f).unwrap_or_else(|| f(&[[Row::EMPTY; LANES]; K], &[A::Tail::EMPTY; LANES]))
    }

    /// Spans whose tails are all empty alone (their heads' resolve), the others in groups of
    /// [`HT_RESOLVE_GROUP`] (`lanes::hybrid_resolve_parts{2,4}_rgba8`: the tails' dependency
    /// chains of the group's spans overlap), the last ones two at a time and alone.
    #[inline(always)]
    fn resolve_line_rgba8<L: Arrangement>(line: &[Row], out: &mut [[[u8; 4]; LANES]], bg: IntBackground) {
        let unit = LANES * Self::ROWS;
        let at = |i: usize| line.get(i * unit..(i + 1) * unit).unwrap_or(&[]);
        let mut put = |j: usize, r: Option<[[u8; 4]; LANES]>| {
            if let Some(o) = out.get_mut(j) {
                *o = r.unwrap_or_else(|| Self::resolve_unit_rgba8::<L>(at(j), bg));
            }
        };
        let pair = |i0: usize, i1: usize| {
            Self::view::<L, _>(at(i0), |h0, t0| {
                Self::view::<L, _>(at(i1), |h1, t1| {
                    lanes::hybrid_resolve_parts2_rgba8([(h0, t0), (h1, t1)], bg)
                })
            })
            .flatten()
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
            let [i0, i1, i2, i3] = group;
            if HT_RESOLVE_GROUP == 2 {
                let two = pair(i0, i1);
                put(i0, two.map(|r| r[0]));
                put(i1, two.map(|r| r[1]));
                continue;
            }
            let four = Self::view::<L, _>(at(i0), |h0, t0| {
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
            .flatten();
            for (k, j) in group.into_iter().enumerate() {
                put(j, four.map(|r| r[k & 3]));
            }
        }
        let rest = group.get(..len).unwrap_or(&[]);
        let mut pairs = rest.chunks_exact(2);
        for p in &mut pairs {
            if let [i0, i1] = *p {
                let two = pair(i0, i1);
                put(i0, two.map(|r| r[0]));
                put(i1, two.map(|r| r[1]));
            }
        }
        for &j in pairs.remainder() {
            put(j, None);
        }
    }

    /// The integer resolve of an empty pixel (as MLAB's: an empty tail adds nothing).
    /// An empty pixel's integer resolve (empty head rows, empty tail).
    fn clear_rgba8(background: Background) -> [[u8; 4]; LANES] {
        [crate::resolve::int::ht_rgba8(&[Row::EMPTY; K], A::Tail::EMPTY, background); LANES]
    }
}
