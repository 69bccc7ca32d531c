//! `rows_from_bytes`: arbitrary rows and tails, in both arithmetics: the layouts of the row
//! and of both tails, both merges, the resolves, Listing 1 and 2 on any contents, and the lanes
//! kernel on garbage (see the crate docs' table).

use mlab::glam::Vec3;
use mlab::half::f16;
use mlab::lanes::{self, HybridSpan, LANES};
use mlab::{
    Background, Hybrid, Paper, Resolved, Row, TailFormat, Unbiased, hybrid, hybrid::PaperTail, mlab as mlab_mod,
    resolve_rows, to_rgba8, to_rgba16f,
};
use mlab_reference::lanes::{check_hybrid_span, check_mlab_span};
use mlab_reference::model::{Model, composite_rows_f64, ref_bubble, ref_row_hash, ref_tail_fields, tail_f64};

use super::{check_int_resolve, from_pixel_major, is_default, lanes_ok, tail_color_limit, to_pixel_major};
use crate::check::{check_close, check_invariants, check_resolved, invariants_hold};
use crate::input::Input;

/// Bytes of a row, or `fill` when the input is exhausted.
fn row_or(input: &mut Input, fill: Row) -> Row {
    input.array::<8>().map(Row::from_bytes).unwrap_or(fill)
}

/// Layout of any 8 bytes as a row and as a tail of both layouts, checked against the
/// documented tables.
pub fn check_layout(b: [u8; 8]) {
    let w = [
        u32::from_le_bytes([b[0], b[1], b[2], b[3]]),
        u32::from_le_bytes([b[4], b[5], b[6], b[7]]),
    ];
    let row = Row::from_bytes(b);
    assert_eq!(row.to_bytes(), b);
    assert_eq!(row.words(), w);
    assert_eq!(Row::from_words(w), row);
    assert_eq!(row.color(), [b[0], b[1], b[2]]);
    assert_eq!(row.transmittance(), b[3]);
    assert_eq!((row.color(), row.transmittance()), ([b[0], b[1], b[2]], b[3]));
    assert_eq!(row.depth().to_bits(), w[1]);
    assert_eq!(row.is_empty(), b == [0, 0, 0, 255, 0, 0, 0x80, 0x7f]);
    assert_eq!(row.is_invisible(), b[..4] == [0, 0, 0, 255]);
    // The paper's tail: two words, spare bits 30..32 of word0.
    let tail = PaperTail::from_bytes(b);
    assert_eq!(tail.to_bytes(), b);
    assert_eq!(mlab::Row::from_bytes(tail.to_bytes()).words(), w);
    assert_eq!(
        <PaperTail as mlab::TailFormat>::from_bytes(mlab::Row::from_words(w).to_bytes()),
        tail
    );
    assert_eq!(
        tail.color_sum(),
        [w[0] & 1023, (w[0] >> 10) & 1023, (w[0] >> 20) & 1023]
    );
    assert_eq!(tail.alpha_sum(), w[1] & 0xffff);
    assert_eq!(tail.count(), w[1] >> 16);
    check_tail_fields::<Paper>(b);
    // The wide tail: one little-endian u64.
    let v = u64::from_le_bytes(b);
    let wide = mlab::Tail::from_bytes(b);
    assert_eq!(wide.to_bytes(), b);
    assert_eq!(u64::from_le_bytes(wide.to_bytes()), v);
    assert_eq!(mlab::Row::from_bytes(wide.to_bytes()).words(), w);
    assert_eq!(
        <mlab::Tail as mlab::TailFormat>::from_bytes(mlab::Row::from_words(w).to_bytes()),
        wide
    );
    check_tail_fields::<Unbiased>(b);
}

/// The tail of `A` read from any 8 bytes: fields equal to the reference layout's,
/// `saturated` exactly when a field is at its maximum, and `from_sums` saturating each
/// field (with the spare bits 0), for the fields as read and for values past them.
fn check_tail_fields<A: Model>(b: [u8; 8]) {
    let layout = A::TAIL;
    assert_eq!(
        layout.max(0),
        u64::from(<A::Tail as TailFormat>::COLOR_MAX),
        "{}: the reference color field and the kernel's COLOR_MAX differ",
        A::NAME
    );
    let t = <A::Tail as TailFormat>::from_bytes(b);
    let f = layout.fields(b);
    assert_eq!(tail_fields(t), f, "{} tail fields of {b:02x?}", A::NAME);
    assert_eq!(t.saturated(), layout.saturated(b), "{} saturated() of {t:?}", A::NAME);
    let sums = |f: [u64; 5]| {
        let f = f.map(|x| u32::try_from(x).unwrap_or(u32::MAX));
        <A::Tail as TailFormat>::from_sums([f[0], f[1], f[2]], f[3], f[4]).to_bytes()
    };
    assert_eq!(sums(f), layout.pack(f, [0; 8]), "{} from_sums of {f:?}", A::NAME);
    // Past the maxima: the raw bytes as larger numbers (bits beyond the field kept).
    let v = u64::from_le_bytes(b);
    let big: [u64; 5] = core::array::from_fn(|i| (v >> (8 * i)) & 0xff_ffff);
    let sat: [u64; 5] = core::array::from_fn(|i| big[i].min(layout.max(i)));
    assert_eq!(sums(big), layout.pack(sat, [0; 8]), "{} from_sums of {big:?}", A::NAME);
}

fn tail_fields<T: TailFormat>(t: T) -> [u64; 5] {
    let [r, g, b] = t.color_sum();
    [r, g, b, t.alpha_sum(), t.count()].map(u64::from)
}

/// The merge of two arbitrary rows in both arithmetics: byte-equal to the reference
/// merges (the default `mlab::merge` to the unbiased one), each product within
/// `A::MERGE_ERROR` steps of the exact one (T always, colors unless they saturate at 255),
/// and `color <= 255 - T` kept when both rows have it (documented for both arithmetics).
///
/// The hash of the merge (the inserted fragment's) is taken from the rows' bits, so that
/// the input reaches every dither.
pub fn check_merges(front: Row, back: Row) {
    let h = front.words()[1].rotate_left(16) ^ back.words()[0];
    assert_eq!(
        <mlab::Unbiased as mlab::Arithmetic>::merge(front, back, h),
        <Unbiased as Model>::ref_merge(front, back, h),
        "default merge of {front:?}, {back:?}"
    );
    check_merge::<Paper>(front, back, h);
    check_merge::<Unbiased>(front, back, h);
}

fn check_merge<A: Model>(front: Row, back: Row, h: u32) {
    let name = A::NAME;
    let m = <A as mlab::Arithmetic>::merge(front, back, h);
    assert_eq!(m, A::ref_merge(front, back, h), "{name} merge of {front:?}, {back:?}");
    let [fr, fg, fb, ft, ..] = front.to_bytes().map(f64::from);
    let [br, bg, bb, bt, ..] = back.to_bytes().map(f64::from);
    let [mr, mg, mb, mt, ..] = m.to_bytes().map(f64::from);
    let within = |got: f64, exact: f64| (got - exact).abs() < A::MERGE_ERROR + 1e-9;
    assert!(
        within(mt, ft * bt / 255.0),
        "{name} merge T of {front:?}, {back:?}: {m:?}"
    );
    for (got, (a, b)) in [mr, mg, mb].into_iter().zip([(fr, br), (fg, bg), (fb, bb)]) {
        let exact = a + b * ft / 255.0;
        assert!(
            within(got, exact) || (got == 255.0 && exact > 254.0),
            "{name} merge color of {front:?}, {back:?}: {m:?}"
        );
    }
    // The merged depth: the front's (Paper; Unbiased where the back is not behind), else
    // between the two (the opacity-weighted depth, checked bit for bit by `ref_merge`).
    let (zf, zb, z) = (front.depth(), back.depth(), m.depth());
    if A::NAME == "paper" || zb <= zf {
        assert_eq!(
            z.to_bits(),
            zf.to_bits(),
            "{name} merge depth of {front:?}, {back:?}: {m:?}"
        );
    } else if zf < zb {
        assert!(zf <= z && z <= zb, "{name} merge depth of {front:?}, {back:?}: {m:?}");
    }
    let occludes = |r: Row| r.color().iter().all(|&c| c <= 255 - r.transmittance());
    if occludes(front) && occludes(back) {
        assert!(
            occludes(m),
            "{name} merge of {front:?}, {back:?}: {m:?} has color above alpha"
        );
    }
}

/// `rows_from_bytes`: the first byte picks M (1, 2, 3, 4, 8) and K (0, 1, 2, 4, 8); then
/// M rows, a row to insert, K head rows, a tail, a background (missing bytes: empty rows).
/// The MLAB part and the HT part each run on the same bytes in both arithmetics.
pub fn rows_from_bytes(data: &[u8]) {
    for chunk in data.chunks_exact(8) {
        check_layout(chunk.try_into().unwrap());
    }
    for pair in data.chunks_exact(16) {
        let (a, b) = pair.split_at(8);
        let (a, b) = (
            Row::from_bytes(a.try_into().unwrap()),
            Row::from_bytes(b.try_into().unwrap()),
        );
        check_merges(a, b);
        check_merges(b, a);
    }
    let mut input = Input::new(data);
    let Some(sel) = input.u8() else { return };
    let mut paper = input.clone();
    garbage_mlab_a::<Paper>(sel, &mut paper);
    garbage_mlab_a::<Unbiased>(sel, &mut input);
    assert_eq!(
        paper.remaining(),
        input.remaining(),
        "both arithmetics read the same bytes"
    );
    let mut paper = input.clone();
    garbage_hybrid_a::<Paper>(sel, &mut paper);
    garbage_hybrid_a::<Unbiased>(sel, &mut input);
}

fn garbage_mlab_a<A: Model>(sel: u8, input: &mut Input) {
    match sel % 5 {
        0 => garbage_mlab::<1, A>(input),
        1 => garbage_mlab::<2, A>(input),
        2 => garbage_mlab::<3, A>(input),
        3 => garbage_mlab::<4, A>(input),
        _ => garbage_mlab::<8, A>(input),
    }
}

fn garbage_hybrid_a<A: Model>(sel: u8, input: &mut Input) {
    match sel / 5 % 5 {
        0 => garbage_hybrid::<0, A>(input),
        1 => garbage_hybrid::<1, A>(input),
        2 => garbage_hybrid::<2, A>(input),
        3 => garbage_hybrid::<4, A>(input),
        _ => garbage_hybrid::<8, A>(input),
    }
}

fn garbage_mlab<const M: usize, A: Model>(input: &mut Input) {
    let name = A::NAME;
    let rows: [Row; M] = core::array::from_fn(|_| row_or(input, Row::EMPTY));
    let new = row_or(input, Row::EMPTY);
    let context = (name, &rows, new);
    check_merge::<A>(rows[0], new, ref_row_hash(new, 0));

    // Resolve of any rows: finite, in range, and Eq. 5 evaluated in f64.
    let r = resolve_rows(&rows);
    check_resolved(r, M as f32, &context);
    check_close(r, composite_rows_f64(&rows), 1e-5, &context);
    check_pixels(r, input, &context);
    // The integer RGBA8 resolve of any rows: the reference formula, within its bound.
    check_int_resolve(&rows, &context);

    // Insert of any row into any rows: Listing 1 step by step, never a panic.
    let (mut expected, pushed) = ref_bubble(&rows, new);
    let last = expected[M - 1];
    expected[M - 1] = A::ref_merge(last, pushed, ref_row_hash(new, 0));
    let mut after = rows;
    mlab_mod::insert_with::<A, _>(&mut after, new);
    assert_eq!(
        after.as_slice(),
        expected.as_slice(),
        "{name}: insert {new:?} into {rows:?}"
    );
    if is_default::<A>() {
        let mut d = rows;
        mlab_mod::insert_with::<mlab::Unbiased, _>(&mut d, new);
        assert_eq!(d, after, "the default insert is not {name}'s");
    }
    // Rows that satisfied the invariants keep them for any row that is not NaN or a
    // non-empty row at +infinity.
    let new_ok = new.is_empty() || new.depth() < f32::INFINITY;
    if invariants_hold(&rows) && new_ok {
        check_invariants(&after, &context);
    }
    check_resolved(resolve_rows(&after), M as f32, &context);

    // Lanes on garbage: lane l holds the rows rotated by l and gets `new` (even lanes) or
    // one of its own rows (odd lanes, a tie), under a mask from the input.
    let mask = input.u8().unwrap_or(0xff);
    let mut pixels = [rows; LANES];
    let mut rows8 = [new; LANES];
    for (lane, p) in pixels.iter_mut().enumerate() {
        p.rotate_left(lane % M);
        if lane % 2 == 1 {
            rows8[lane] = p[lane % M];
        }
    }
    let mut span = from_pixel_major(&pixels);
    lanes_ok(check_mlab_span(&span, &pixels));
    lanes::mlab_insert_with::<A, _>(&mut span, &rows8, mask);
    for (lane, p) in pixels.iter_mut().enumerate() {
        if mask >> lane & 1 == 1 {
            mlab_mod::insert_with::<A, _>(p, rows8[lane]);
        }
    }
    assert_eq!(
        to_pixel_major(&span),
        pixels,
        "{name}: lanes insert on garbage rows {rows:?}, mask {mask:#010b}"
    );
    lanes_ok(check_mlab_span(&span, &pixels));
}

fn garbage_hybrid<const K: usize, A: Model>(input: &mut Input) {
    let name = A::NAME;
    let layout = A::TAIL;
    let head: [Row; K] = core::array::from_fn(|_| row_or(input, Row::EMPTY));
    let tail_bytes = input.array::<8>().unwrap_or([0; 8]);
    let tail = <A::Tail as TailFormat>::from_bytes(tail_bytes);
    let new = row_or(input, Row::EMPTY);
    let context = (name, &head, tail, new);

    check_tail_resolve::<A>(tail_bytes);

    let limit = tail_color_limit::<A>();
    let r = Hybrid::<K, A>::from_parts(head, tail).resolve();
    check_resolved(r, K as f32 + limit, &context);
    check_pixels(r, input, &context);

    // Listing 2 on any head and tail: the head is the bubble, the tail adds the pushed-out
    // row field by field, saturating, unless it is invisible; spare bits are kept.
    let (expected_head, pushed) = ref_bubble(&head, new);
    let fields = layout.fields(tail_bytes);
    let expected_tail = layout.pack(ref_tail_fields(layout, fields, &[pushed]), tail_bytes);
    let (mut h, mut t) = (head, tail);
    hybrid::insert(&mut h, &mut t, new);
    assert_eq!(
        h.as_slice(),
        expected_head.as_slice(),
        "{name}: HT insert {new:?} into {head:?}"
    );
    assert_eq!(
        t.to_bytes(),
        expected_tail,
        "{name}: HT tail after {new:?} into {tail:?}: {t:?}, expected {:?}",
        layout.fields(expected_tail)
    );
    let mut px = Hybrid::<K, A>::from_parts(head, tail);
    px.insert_row(new);
    assert_eq!((px.head(), px.tail()), (&h, t), "{name}: Hybrid::insert_row");
    let new_ok = new.is_empty() || new.depth() < f32::INFINITY;
    if invariants_hold(&head) && new_ok {
        check_invariants(&h, &context);
    }
    check_resolved(px.resolve(), K as f32 + limit, &context);

    // Lanes on garbage.
    let mask = input.u8().unwrap_or(0xff);
    check_hybrid_lanes::<K, A>(head, tail_bytes, new, mask);
}

/// An HT tail of any bytes alone: finite, in range, and Bavoil-Myers evaluated in f64 from
/// the fields of the reference layout.
fn check_tail_resolve<A: Model>(tail_bytes: [u8; 8]) {
    let name = A::NAME;
    let layout = A::TAIL;
    let tail = <A::Tail as TailFormat>::from_bytes(tail_bytes);
    // Precision of the f32 evaluation: `1 - mean` is rounded (2^-25 absolute) and raised to
    // the power n, so |dT| <= n 2^-24 (+ the multiplies); the color is `S_c (1 - T) / S_a`,
    // so its error is that of T divided by S_a. The same bounds for both layouts: they
    // depend on the count n, not on the field widths.
    let t = tail.resolve();
    let limit = tail_color_limit::<A>();
    check_resolved(t, limit, &tail);
    let fields = layout.fields(tail_bytes);
    let (c_ref, t_ref) = tail_f64(fields);
    let n = fields[4].max(1) as f64;
    let dt = 1e-5 + n * 2f64.powi(-24);
    let err = (f64::from(t.transmittance) - t_ref).abs();
    assert!(
        err <= dt,
        "{name} tail T: {t:?} vs {t_ref}, error {err} > {dt}, from {tail:?}"
    );
    let c = t.color.to_array();
    for i in 0..3 {
        let sum = fields[i] as f64 / 255.0;
        // What an evaluation without cancellation gives (the kernel's geometric sum since
        // the fix of finding F1b): n 2^-23 relative, always. The bound of the evaluation as
        // printed, `|dT| / S_a` relative, about `1 / (2 S_a)` times looser (128x at an alpha
        // sum of one byte: where F1b lived), went with the MLAB_FUZZ_STRICT switch that
        // chose between them.
        let bound = if fields[3] == 0 {
            1e-5
        } else {
            sum * (2e-5 + n * 2f64.powi(-23)) + 1e-5
        };
        let err = (f64::from(c[i]) - c_ref[i]).abs();
        assert!(
            err <= bound,
            "{name} tail color {i}: {t:?} vs {c_ref:?}, error {err} > {bound}, from {tail:?}"
        );
    }
}

/// Lanes on garbage: lane l holds the head rotated by l and the tail bytes rotated by l, and
/// gets `new` in the lanes of `mask`; the lanes kernel against the scalar one.
fn check_hybrid_lanes<const K: usize, A: Model>(head: [Row; K], tail_bytes: [u8; 8], new: Row, mask: u8) {
    let mut pixels = [Hybrid::<K, A>::new(); LANES];
    for (lane, p) in pixels.iter_mut().enumerate() {
        let mut hd = head;
        if K > 0 {
            hd.rotate_left(lane % K);
        }
        let mut tb = tail_bytes;
        tb.rotate_left(lane);
        *p = Hybrid::from_parts(hd, <A::Tail as TailFormat>::from_bytes(tb));
    }
    let mut span = HybridSpan::<K, A>::default();
    for (lane, p) in pixels.iter().enumerate() {
        for j in 0..K {
            span.head[j][lane] = p.head()[j];
        }
        span.tails[lane] = p.tail();
    }
    lanes_ok(check_hybrid_span(&span, &pixels));
    let rows8 = [new; LANES];
    lanes::hybrid_insert(&mut span, &rows8, mask);
    for (lane, p) in pixels.iter_mut().enumerate() {
        if mask >> lane & 1 == 1 {
            p.insert_row(new);
        }
    }
    lanes_ok(check_hybrid_span(&span, &pixels));
}

/// The pixel writers on a resolved value and a background read from the input (any bits:
/// backgrounds are not validated; NaN gives byte 0 and a NaN half).
fn check_pixels(r: Resolved, input: &mut Input, context: &dyn core::fmt::Debug) {
    let bg = Vec3::new(
        input.unit().unwrap_or(0.0),
        input.unit().unwrap_or(0.5),
        input.unit().unwrap_or(1.0),
    );
    for background in [Background::Opaque(bg), Background::Transparent] {
        let p = r.pixel(background);
        let bytes = to_rgba8(p);
        let halves = to_rgba16f(p);
        for i in 0..4 {
            let x = p.to_array()[i];
            let want = if x.is_nan() {
                0
            } else {
                (f64::from(x.clamp(0.0, 1.0)) * 255.0 + 0.5).floor() as u8
            };
            assert!(
                bytes[i].abs_diff(want) <= 1,
                "rgba8 of {p:?} = {bytes:?} from {context:?}"
            );
            assert_eq!(halves[i].to_bits(), f16::from_f32(x).to_bits());
        }
        if let Background::Transparent = background {
            assert!((0.0..=1.0).contains(&p.w), "premultiplied alpha {p:?} from {context:?}");
        }
    }
}
