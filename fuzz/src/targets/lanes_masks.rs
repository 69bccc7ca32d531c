//! `lanes_masks`: the first byte picks the kind (MLAB with M = 1, 2, 4 or HT with
//! K = 0, 1, 3), then width, height, storage length, contents, and a list of operations.
//!
//! Spans of up to 8 pixels with an 8-bit mask, starting anywhere (also past the right and
//! bottom edges), go through the scalar framebuffer one pixel per lane, through the span
//! framebuffer, and through the lanes kernel (`mlab::lanes::mlab_insert` / `hybrid_insert`,
//! gathered from and scattered to the same storage, lanes outside the buffer holding a
//! sentinel and masked off). Pixels that are off, or outside the buffer, never change (in
//! the storage and in the lanes span); guard rows never change; an error changes nothing;
//! the lanes storage equals the scalar storage byte for byte; the pixels equal the
//! reference side of the kind ([`RefKind`]) pixel by pixel.
//!
//! Every input runs in both arithmetics (the same operations on the same contents).
//!
//! One run ([`spans`]) is its setup ([`Fixture::setup`]), then up to 32 operations, each a
//! function of [`Fixture`] ([`Fixture::span_op`]: the lanes kernel, the span framebuffer and
//! the pixel inserts; [`Fixture::resolve_op`]; [`Fixture::clear_op`]), and the checks after
//! each ([`Fixture::check_after`]).

use core::marker::PhantomData;

use mlab::glam::{Vec3, Vec4};
use mlab::half::f16;
use mlab::lanes::LANES;
use mlab::{
    Background, Fragment, Framebuffer, FramebufferError, Grid, Paper, PixelMajor, Row, Spans, Unbiased, to_rgba16f,
};
use mlab_reference::model::{Model, ref_fragment_hash, ref_key};
use mlab_reference::{HtKind, MlabKind, RefKind};

use super::{OFF_LANE_ROW, in_both_arithmetics};
use crate::check::{check_resolved, validate};
use crate::input::Input;

/// `lanes_masks` (see the module docs).
pub fn lanes_masks(data: &[u8]) {
    in_both_arithmetics(data, lanes_masks_a::<Paper>, lanes_masks_a::<Unbiased>);
}

fn lanes_masks_a<A: Model>(sel: u8, mut input: Input) {
    match sel % 6 {
        0 => spans::<MlabKind<1, A>>(&mut input),
        1 => spans::<MlabKind<2, A>>(&mut input),
        2 => spans::<MlabKind<4, A>>(&mut input),
        3 => spans::<HtKind<0, A>>(&mut input),
        4 => spans::<HtKind<1, A>>(&mut input),
        _ => spans::<HtKind<3, A>>(&mut input),
    }
}

/// Guard rows on each side of the storage handed to the framebuffer.
const GUARD: usize = 3;
/// A guard row (a pattern no operation writes).
const GUARD_ROW: Row = Row::new([0xde, 0xad, 0xbe], 0xef, -1234.5);
/// Operations per input at the most.
const MAX_OPS: usize = 32;

/// The pixel-major framebuffer of a kind.
type View<'a, K> = Grid<'a, <K as RefKind>::P, PixelMajor>;

/// The span framebuffer of a kind over `s` (its storage is always of the right length).
fn span_view<K: RefKind>(s: &mut [Row], w: u32, h: u32) -> Grid<'_, K::P, Spans> {
    Grid::new(s, w, h).expect("span storage")
}

/// Lanes of the span `x0 .. x0 + 8` that lie inside a `w x h` buffer on line `y`.
fn inside(w: u32, h: u32, x0: u32, y: u32) -> u8 {
    (0..LANES as u32)
        .filter(|&l| x0 + l < w && y < h)
        .fold(0, |m, l| m | 1 << l)
}

/// The sentinel row of lane `lane`, layer `j` of a span (outside the buffer).
fn sentinel(lane: usize, j: usize) -> Row {
    Row::new([lane as u8, j as u8, 0x5a], 0x33, -(lane as f32) - 0.5)
}

/// Index of slot 0 of pixel `(x, y)` in the guarded pixel-major storage of a framebuffer of
/// width `w`.
fn pixel_index<K: RefKind>(w: u32, x: u32, y: u32) -> usize {
    GUARD + (y as usize * w as usize + x as usize) * K::SLOTS
}

/// `(x, y)` out of the bounds of a `w x h` framebuffer.
fn out_of_bounds(x: u32, y: u32, w: u32, h: u32) -> FramebufferError {
    FramebufferError::OutOfBounds {
        x,
        y,
        width: w,
        height: h,
    }
}

/// What an operation returns to the loop of [`spans`].
enum Flow {
    /// Run the checks after the operation.
    Check,
    /// An invalid fragment: next operation, no checks (nothing was done).
    Skip,
    /// The input ran out: stop.
    Stop,
}

/// What the checks after one operation compare with.
struct Step {
    /// The pixel-major storage (guard rows included) before the operation.
    before: Vec<Row>,
    /// What it must be after the operation: the per-pixel reference.
    expected: Vec<Row>,
    /// The storage after the same span through the lanes kernel, if it was a span.
    lanes: Option<Vec<Row>>,
}

/// One span operation, as read from the input.
struct SpanOp {
    x0: u32,
    y: u32,
    /// Pixels `x0 .. x0 + n` (`n` in 0..=8).
    n: u32,
    /// The mask as read (lane `i` on if bit `i`; only the first `n` count).
    mask: u8,
    /// The first `n` bits of `mask`.
    span_mask: u8,
    f: Fragment,
    /// Each lane's reference row of `f` in its pixel.
    rows: [Row; LANES],
    /// Each lane's reference hash of `f` in its pixel (`Framebuffer::pixel_id`).
    hashes: [u32; LANES],
}

/// A `w x h` framebuffer of the kind `K` in both arrangements: pixel-major storage between
/// guard rows, and the same pixels in a span framebuffer, placed by the documented formula
/// `((y * spans + x / 8) * R + j) * 8 + x % 8`, its padding lanes holding a sentinel that no
/// insert may touch.
struct Fixture<K> {
    w: u32,
    h: u32,
    /// Rows of the pixel-major storage: the right length (checked by the setup).
    len: usize,
    /// `GUARD` guard rows, the pixel-major storage, `GUARD` guard rows.
    buf: Vec<Row>,
    /// The span framebuffer's storage.
    sbuf: Vec<Row>,
    kind: PhantomData<K>,
}

/// `lanes_masks` on one kind: the setup, then up to [`MAX_OPS`] operations, each followed by
/// its checks.
fn spans<K: RefKind>(input: &mut Input) {
    let Some(mut fx) = Fixture::<K>::setup(input) else {
        return;
    };
    for _ in 0..MAX_OPS {
        let Some(op) = input.u8() else { break };
        let before = fx.buf.clone();
        let mut step = Step {
            expected: before.clone(),
            before,
            lanes: None,
        };
        let flow = match op % 4 {
            // A span: pixels x0 .. x0 + n on line y, lane i on if bit i of the mask.
            0 | 1 => fx.span_op(input, &mut step),
            // Resolve every pixel into an output of the right length, or one off.
            2 => fx.resolve_op(input, &step.before),
            _ => fx.clear_op(&mut step.expected),
        };
        match flow {
            Flow::Check => fx.check_after(op, &step),
            Flow::Skip => continue,
            Flow::Stop => break,
        }
    }
}

impl<K: RefKind> Fixture<K> {
    /// Read the size, the storage length and contents; check the pixel-major view's
    /// validation of the length (a refused storage ends the run: `None`), then copy the
    /// pixels into the span framebuffer.
    fn setup(input: &mut Input) -> Option<Self> {
        let (Some(w), Some(h), Some(len_sel), Some(fill)) = (input.u8(), input.u8(), input.u8(), input.u8()) else {
            return None;
        };
        let (w, h) = (u32::from(w % 12) + 1, u32::from(h % 5) + 1);
        let needed = w as usize * h as usize * K::SLOTS;
        // Mostly the right length; sometimes one row short or long, or none at all.
        let len = match len_sel % 16 {
            13 => needed.saturating_sub(1),
            14 => needed + 1,
            15 => 0,
            _ => needed,
        };
        let mut buf = vec![GUARD_ROW; len + 2 * GUARD];
        for (i, slot) in buf[GUARD..GUARD + len].iter_mut().enumerate() {
            // Empty storage, or storage read back from arbitrary bytes (fill pattern + input).
            *slot = if fill & 1 == 0 {
                Row::EMPTY
            } else {
                input
                    .array::<8>()
                    .map(Row::from_bytes)
                    .unwrap_or(Row::new([fill, i as u8, 0], fill, i as f32))
            };
        }
        if !check_view::<K>(&mut buf, w, h, needed) {
            return None;
        }
        let mut fx = Fixture {
            w,
            h,
            len,
            buf,
            sbuf: Vec::new(),
            kind: PhantomData,
        };
        let slen = fx.spans_per_line() * LANES * h as usize * K::SLOTS;
        assert_eq!(Grid::<K::P, Spans>::rows_needed(w, h), Ok(slen));
        fx.sbuf = vec![sentinel(7, 7); slen];
        for y in 0..h as usize {
            for x in 0..w as usize {
                for j in 0..K::SLOTS {
                    let (i, p) = (fx.sidx(x, y, j), fx.pixel(x as u32, y as u32));
                    fx.sbuf[i] = fx.buf[p + j];
                }
            }
        }
        Some(fx)
    }

    /// Spans of the span framebuffer per line.
    fn spans_per_line(&self) -> usize {
        (self.w as usize).div_ceil(LANES)
    }

    /// Index in `buf` of slot 0 of pixel `(x, y)`.
    fn pixel(&self, x: u32, y: u32) -> usize {
        pixel_index::<K>(self.w, x, y)
    }

    /// Index in `sbuf` of slot `j` of pixel `(x, y)` (or of a padding lane).
    fn sidx(&self, x: usize, y: usize, j: usize) -> usize {
        ((y * self.spans_per_line() + x / LANES) * K::SLOTS + j) * LANES + x % LANES
    }

    /// The pixel-major storage without its guard rows.
    fn storage(buf: &mut [Row], len: usize) -> &mut [Row] {
        &mut buf[GUARD..GUARD + len]
    }

    // -----------------------------------------------------------------------------------
    // Span insert: the lanes kernel, the span framebuffer, the pixel inserts

    /// A span of one fragment through the lanes kernel (on a copy of the storage), the span
    /// framebuffer and the pixel-major framebuffer pixel by pixel (with the per-pixel
    /// reference into `step.expected`).
    fn span_op(&mut self, input: &mut Input, step: &mut Step) -> Flow {
        let s = match self.read_span(input) {
            Ok(s) => s,
            Err(flow) => return flow,
        };
        let mut lanes_buf = step.before.clone();
        self.lanes_span(Self::storage(&mut lanes_buf, self.len), &s);
        step.lanes = Some(lanes_buf);
        self.span_insert(&s);
        self.pixel_inserts(&s, &mut step.expected);
        Flow::Check
    }

    /// Read a span operation: `x0`, `y`, `n`, the mask and a fragment; an invalid fragment
    /// is [`Flow::Skip`], missing bytes [`Flow::Stop`].
    fn read_span(&self, input: &mut Input) -> Result<SpanOp, Flow> {
        let (w, h) = (self.w, self.h);
        let (Some(x0), Some(y), Some(n), Some(mask)) = (input.u8(), input.u8(), input.u8(), input.u8()) else {
            return Err(Flow::Stop);
        };
        let Some(raw) = input.raw_fragment() else {
            return Err(Flow::Stop);
        };
        let Some(f) = validate(&raw) else {
            return Err(Flow::Skip);
        };
        let (x0, y, n) = (u32::from(x0) % (w + 4), u32::from(y) % (h + 2), u32::from(n % 9));
        // The lanes kernel on a copy: lanes 0 .. n of the mask, at the same place.
        let span_mask = (mask as u16 & ((1u16 << n) - 1)) as u8;
        // Each lane's pixel id, reference hash and row (`Framebuffer::pixel_id`).
        let pid = |lane: u32| y.wrapping_mul(w).wrapping_add(x0).wrapping_add(lane);
        let hashes: [u32; LANES] = core::array::from_fn(|l| ref_fragment_hash(ref_key(&f), pid(l as u32)));
        let rows: [Row; LANES] = core::array::from_fn(|l| K::A::ref_row(&f, pid(l as u32)));
        Ok(SpanOp {
            x0,
            y,
            n,
            mask,
            span_mask,
            f,
            rows,
            hashes,
        })
    }

    /// The span `x0 .. x0 + 8` of line `y` through the lanes kernel on `storage`: gather the
    /// pixels into a lanes span (lanes outside the buffer hold a sentinel), insert the rows
    /// in the lanes of the mask that are inside, check that every other lane is unchanged,
    /// scatter back.
    fn lanes_span(&self, storage: &mut [Row], s: &SpanOp) {
        let (w, h, x0, y, mask) = (self.w, self.h, s.x0, s.y, s.span_mask);
        let inside = inside(w, h, x0, y);
        let on = mask & inside;
        let base = |lane: usize| (y as usize * w as usize + x0 as usize + lane) * K::SLOTS;
        let mut span: Vec<[Row; LANES]> = (0..K::SLOTS)
            .map(|j| core::array::from_fn(|lane| sentinel(lane, j)))
            .collect();
        for lane in (0..LANES).filter(|&l| inside >> l & 1 == 1) {
            for (j, layer) in span.iter_mut().enumerate() {
                layer[lane] = storage[base(lane) + j];
            }
        }
        let before = span.clone();
        let rows: [Row; LANES] = core::array::from_fn(|l| if on >> l & 1 == 1 { s.rows[l] } else { OFF_LANE_ROW });
        K::lanes_insert(&mut span, &rows, &s.hashes, on);
        for lane in (0..LANES).filter(|&l| on >> l & 1 == 0) {
            for j in 0..K::SLOTS {
                assert_eq!(
                    span[j][lane], before[j][lane],
                    "lane {lane} slot {j} is off (mask {mask:#010b}) but changed"
                );
            }
        }
        for lane in (0..LANES).filter(|&l| inside >> l & 1 == 1) {
            for (j, layer) in span.iter().enumerate() {
                storage[base(lane) + j] = layer[lane];
            }
        }
    }

    /// The span framebuffer: refused (and unchanged) if an on lane is outside, then the same
    /// span with those lanes off.
    fn span_insert(&mut self, s: &SpanOp) {
        let (w, h, x0, y, span_mask) = (self.w, self.h, s.x0, s.y, s.span_mask);
        let rows8: [Row; LANES] = core::array::from_fn(|l| {
            if span_mask >> l & 1 == 1 {
                s.rows[l]
            } else {
                OFF_LANE_ROW
            }
        });
        let top = (0..LANES as u32).filter(|&l| span_mask >> l & 1 == 1).max();
        let expected_err = if y >= h {
            Some(out_of_bounds(x0, y, w, h))
        } else {
            top.filter(|&l| x0 + l >= w).map(|l| out_of_bounds(x0 + l, y, w, h))
        };
        let sbefore = self.sbuf.clone();
        let got = span_view::<K>(&mut self.sbuf, w, h).insert_span_hashed(x0, y, &rows8, &s.hashes, span_mask);
        match expected_err {
            Some(e) => {
                assert_eq!(got, Err(e), "span ({x0}, {y}) mask {span_mask:#010b} in {w}x{h}");
                assert_eq!(self.sbuf, sbefore, "a refused span changed the span framebuffer");
                let on = span_mask & inside(w, h, x0, y);
                if on != 0 {
                    assert_eq!(
                        span_view::<K>(&mut self.sbuf, w, h).insert_span_hashed(x0, y, &rows8, &s.hashes, on),
                        Ok(())
                    );
                }
            }
            None => assert_eq!(got, Ok(())),
        }
    }

    /// The pixel inserts of the span's on lanes into the pixel-major framebuffer (refused
    /// outside it), and the reference insert of each into `expected`.
    fn pixel_inserts(&mut self, s: &SpanOp, expected: &mut [Row]) {
        let (w, h, y) = (self.w, self.h, s.y);
        for lane in (0..s.n).filter(|&l| s.mask >> l & 1 == 1) {
            let x = s.x0 + lane;
            let got = View::<K>::new(Self::storage(&mut self.buf, self.len), w, h)
                .expect("accepted by the setup")
                .insert(x, y, &s.f);
            if x < w && y < h {
                assert_eq!(got, Ok(()));
                let p = self.pixel(x, y);
                K::ref_insert(
                    &mut expected[p..p + K::SLOTS],
                    s.rows[lane as usize],
                    s.hashes[lane as usize],
                );
            } else {
                assert_eq!(got, Err(out_of_bounds(x, y, w, h)));
            }
        }
    }

    // -----------------------------------------------------------------------------------
    // Resolve and clear

    /// Resolve every pixel with one of the three writers into an output of the right length,
    /// or one off, in both arrangements; then one pixel's contents and resolve, inside or
    /// outside.
    fn resolve_op(&mut self, input: &mut Input, before: &[Row]) -> Flow {
        let (Some(which), Some(off), Some(b)) = (input.u8(), input.u8(), input.u8()) else {
            return Flow::Stop;
        };
        let pixels = (self.w * self.h) as usize;
        let n = match off % 8 {
            6 => pixels - 1,
            7 => pixels + 1,
            _ => pixels,
        };
        let bg = if b == 255 {
            Background::Transparent
        } else {
            Background::Opaque(Vec3::splat(f32::from(b) / 254.0))
        };
        self.check_resolve_all(before, which, n, bg);
        let (Some(x), Some(y)) = (input.u8(), input.u8()) else {
            return Flow::Stop;
        };
        self.check_pixel(before, u32::from(x), u32::from(y) % (self.h + 2));
        Flow::Check
    }

    /// One whole-framebuffer resolve (`which`) into `n` pixels: the span framebuffer's equal
    /// to the pixel-major one's; refused and unwritten if `n` is not the pixel count, else
    /// every pixel the reference resolve of its slots in `before`.
    fn check_resolve_all(&mut self, before: &[Row], which: u8, n: usize, bg: Background) {
        let (w, h) = (self.w, self.h);
        let pixels = (w * h) as usize;
        let sentinel_px = Vec4::new(7.0, 7.0, 7.0, 7.0);
        let mut out = vec![sentinel_px; n];
        let v = View::<K>::new(Self::storage(&mut self.buf, self.len), w, h).expect("accepted by the setup");
        let got = resolve_all(&v, which, &mut out, bg);
        let mut sout = vec![sentinel_px; n];
        assert_eq!(
            resolve_all(&span_view::<K>(&mut self.sbuf, w, h), which, &mut sout, bg),
            got,
            "span fb resolve result"
        );
        assert_eq!(sout, out, "span fb resolve differs from the pixel-major resolve");
        if n != pixels {
            assert_eq!(
                got,
                Err(FramebufferError::OutputLength {
                    expected: pixels,
                    actual: n
                })
            );
            assert!(
                out.iter().all(|&p| p == sentinel_px),
                "a refused resolve wrote its output"
            );
            return;
        }
        assert_eq!(got, Ok(()));
        for y in 0..h {
            for x in 0..w {
                let p = pixel_index::<K>(w, x, y);
                let slots = &before[p..p + K::SLOTS];
                let r = K::ref_resolve(slots);
                assert_eq!(v.resolve(x, y), Ok(r));
                check_resolved(r, K::max_color(), &(x, y));
                let want = r.pixel(bg);
                let want = match which % 3 {
                    0 => want,
                    1 => Vec4::from_array(K::ref_rgba8(slots, bg).map(f32::from)),
                    _ => Vec4::from_array(to_rgba16f(want).map(f16::to_f32)),
                };
                assert_eq!(out[(y * w + x) as usize], want, "pixel ({x}, {y})");
            }
        }
    }

    /// One pixel's contents in the span framebuffer (its slots in `before`, or refused
    /// outside), and the pixel-major resolve refused outside.
    fn check_pixel(&mut self, before: &[Row], x: u32, y: u32) {
        let (w, h) = (self.w, self.h);
        let sp = span_view::<K>(&mut self.sbuf, w, h).pixel(x, y).map(K::slots);
        if x < w && y < h {
            let p = self.pixel(x, y);
            assert_eq!(sp, Ok(before[p..p + K::SLOTS].to_vec()), "span fb pixel ({x}, {y})");
        } else {
            assert_eq!(sp, Err(out_of_bounds(x, y, w, h)));
            let v = View::<K>::new(Self::storage(&mut self.buf, self.len), w, h).expect("accepted by the setup");
            assert_eq!(v.resolve(x, y), Err(out_of_bounds(x, y, w, h)));
        }
    }

    /// Clear both framebuffers (the span framebuffer's padding back to the sentinel), and
    /// every pixel of `expected`.
    fn clear_op(&mut self, expected: &mut [Row]) -> Flow {
        let (w, h) = (self.w, self.h);
        span_view::<K>(&mut self.sbuf, w, h).clear();
        for y in 0..h as usize {
            for x in w as usize..self.spans_per_line() * LANES {
                for j in 0..K::SLOTS {
                    // Clearing resets the padding too; put the sentinel back.
                    let i = self.sidx(x, y, j);
                    self.sbuf[i] = sentinel(7, 7);
                }
            }
        }
        View::<K>::new(Self::storage(&mut self.buf, self.len), w, h)
            .expect("accepted by the setup")
            .clear();
        for p in 0..(w * h) as usize {
            let p = GUARD + p * K::SLOTS;
            K::cleared(&mut expected[p..p + K::SLOTS]);
        }
        Flow::Check
    }

    // -----------------------------------------------------------------------------------
    // The checks after each operation

    /// Guard rows unchanged; the pixel-major storage equal to the per-pixel reference; the
    /// span framebuffer holding the same pixels and sentinel padding; the lanes kernel's
    /// storage equal to the scalar framebuffer's.
    fn check_after(&self, op: u8, step: &Step) {
        let (w, h, len, buf) = (self.w, self.h, self.len, &self.buf);
        assert_eq!(
            buf[..GUARD],
            step.before[..GUARD],
            "guard rows before the storage changed"
        );
        assert_eq!(
            buf[GUARD + len..],
            step.before[GUARD + len..],
            "guard rows after the storage changed"
        );
        assert_eq!(
            *buf, step.expected,
            "{w}x{h}: pixels differ from the per-pixel reference after op {op}"
        );
        self.span_matches(&op);
        if let Some(lanes_buf) = &step.lanes {
            assert_eq!(
                lanes_buf, buf,
                "{w}x{h}: the lanes span differs from the scalar framebuffer"
            );
        }
    }

    /// The span framebuffer holds the pixel-major pixels, and the sentinel in its padding.
    fn span_matches(&self, context: &dyn core::fmt::Debug) {
        for y in 0..self.h as usize {
            for x in 0..self.w as usize {
                for j in 0..K::SLOTS {
                    assert_eq!(
                        self.sbuf[self.sidx(x, y, j)],
                        self.buf[self.pixel(x as u32, y as u32) + j],
                        "span fb pixel ({x}, {y}) slot {j} after {context:?}"
                    );
                }
            }
            for x in self.w as usize..self.spans_per_line() * LANES {
                for j in 0..K::SLOTS {
                    assert_eq!(
                        self.sbuf[self.sidx(x, y, j)],
                        sentinel(7, 7),
                        "padding lane ({x}, {y}) written after {context:?}"
                    );
                }
            }
        }
    }
}

/// The pixel-major view over `buf` (guard rows, then `len` rows): accepted exactly when the
/// storage has the `needed` rows, with its bytes the rows' bytes; a refusal names the
/// lengths and changes nothing. Returns whether it was accepted.
fn check_view<K: RefKind>(buf: &mut [Row], w: u32, h: u32, needed: usize) -> bool {
    let len = buf.len() - 2 * GUARD;
    let snapshot = buf.to_vec();
    match View::<K>::new(&mut buf[GUARD..GUARD + len], w, h).map(|v| v.as_bytes().to_vec()) {
        Err(e) => {
            assert_ne!(len, needed, "{w}x{h}: storage of the right length refused: {e:?}");
            assert_eq!(
                e,
                FramebufferError::StorageLength {
                    expected: needed,
                    actual: len
                }
            );
            assert_eq!(buf, snapshot, "a refused view changed the storage");
            false
        }
        Ok(view_bytes) => {
            assert_eq!(len, needed, "{w}x{h}: storage of {len} rows accepted, {needed} needed");
            let bytes: Vec<u8> = buf[GUARD..GUARD + len].iter().flat_map(|r| r.to_bytes()).collect();
            assert_eq!(view_bytes, bytes, "as_bytes is not the rows' bytes");
            true
        }
    }
}

/// Run one of the three resolve writers of `v`; bytes and halves are widened to f32 so that
/// errors and untouched outputs compare the same way.
fn resolve_all<F: Framebuffer>(v: &F, which: u8, out: &mut [Vec4], bg: Background) -> Result<(), FramebufferError> {
    match which % 3 {
        0 => v.resolve_into(out, bg),
        1 => {
            let mut px: Vec<[u8; 4]> = out.iter().map(|p| p.to_array().map(|x| x as u8)).collect();
            let r = v.resolve_rgba8(&mut px, bg);
            for (o, p) in out.iter_mut().zip(px) {
                *o = Vec4::from_array(p.map(f32::from));
            }
            r
        }
        _ => {
            let mut px: Vec<[f16; 4]> = out.iter().map(|p| p.to_array().map(f16::from_f32)).collect();
            let r = v.resolve_rgba16f(&mut px, bg);
            for (o, p) in out.iter_mut().zip(px) {
                *o = Vec4::from_array(p.map(f16::to_f32));
            }
            r
        }
    }
}
