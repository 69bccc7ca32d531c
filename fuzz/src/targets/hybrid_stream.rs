//! `hybrid_stream`: a stream of fragments into an HT pixel of K head rows and a tail, in both
//! arithmetics, against a sort-and-sum reference packed in the arithmetic's tail layout after
//! every insert, the lanes kernel, the f64 oracle when the stream fits, and the same bytes for
//! a shuffled and a reversed stream (see the crate docs' table).

use mlab::lanes::{self, HybridSpan, LANES};
use mlab::{Hybrid, Paper, Row, TailFormat, Unbiased};
use mlab_reference::lanes::check_hybrid_span;
use mlab_reference::model::{Model, ref_hybrid};
use mlab_reference::oracle::multilinear_bound;

use super::{
    INT_BACKGROUNDS, MAX_FRAGMENTS, check_int_bound, exact, in_both_arithmetics, lane_mask, lane_rows, lanes_ok,
    occluding, parts, tail_color_limit,
};
use crate::check::{check_close, check_invariants, check_resolved, distinct_depths, validate};
use crate::input::{Ctor, Input};

/// `hybrid_stream`: K from the first byte (0, 1, 2, 4 or 8), then a stream of fragments,
/// then the seed of a permutation; the stream runs in both arithmetics.
pub fn hybrid_stream(data: &[u8]) {
    in_both_arithmetics(data, hybrid_stream_a::<Paper>, hybrid_stream_a::<Unbiased>);
}

fn hybrid_stream_a<A: Model>(sel: u8, mut input: Input) {
    match sel % 5 {
        0 => hybrid_stream_k::<0, A>(&mut input),
        1 => hybrid_stream_k::<1, A>(&mut input),
        2 => hybrid_stream_k::<2, A>(&mut input),
        3 => hybrid_stream_k::<4, A>(&mut input),
        _ => hybrid_stream_k::<8, A>(&mut input),
    }
}

fn hybrid_stream_k<const K: usize, A: Model>(input: &mut Input) {
    let name = A::NAME;
    let mut ht = Hybrid::<K, A>::new();
    let mut span = HybridSpan::<K, A>::default();
    let mut lane_px = [Hybrid::<K, A>::new(); LANES];
    let mut frags = Vec::new();
    let mut rows = Vec::new();
    // The stream ends at a fragment tag 0xff (so the permutation seed can follow) or at the end.
    while frags.len() < MAX_FRAGMENTS {
        let Some(raw) = input.raw_fragment() else { break };
        if raw.ctor == Ctor::PremultipliedRgba && raw.z.to_bits() == 0xffff_ffff {
            break;
        }
        let Some(f) = validate(&raw) else { continue };
        let row = A::ref_row(&f, 0);
        ht.insert(&f);
        let mask = lane_mask(frags.len());
        let rows8 = lane_rows(row, mask);
        lanes::hybrid_insert(&mut span, &rows8, mask);
        for (lane, px) in lane_px.iter_mut().enumerate() {
            if mask >> lane & 1 == 1 {
                px.insert_row(rows8[lane]);
            }
        }
        lanes_ok(check_hybrid_span(&span, &lane_px));
        assert_eq!(lane_px[0], ht);
        frags.push(f);
        rows.push(row);
        let (head, tail) = ref_hybrid(K, &rows, A::TAIL);
        assert_eq!(
            ht.head().as_slice(),
            head.as_slice(),
            "K = {K} {name}: head differs from the reference after {rows:?}"
        );
        assert_eq!(
            ht.tail().to_bytes(),
            tail,
            "K = {K} {name}: tail {:?} differs from the reference {:?} after {rows:?}",
            ht.tail(),
            A::TAIL.fields(tail)
        );
        check_invariants(ht.head(), &rows);
        check_resolved(ht.resolve(), K as f32 + tail_color_limit::<A>(), &rows);
    }
    check_ht_int_resolve(&ht, &rows);
    let n = frags.len();
    let accepted: Vec<_> = frags.iter().map(parts).collect();
    if n <= K {
        assert_eq!(
            ht.tail(),
            <A::Tail as TailFormat>::EMPTY,
            "K = {K} {name}: tail used with {n} fragments"
        );
        if occluding(&accepted) {
            let quant: Vec<f64> = frags.iter().map(|f| A::quant_error(f.alpha())).collect();
            check_close(ht.resolve(), exact(&accepted), multilinear_bound(&quant), &accepted);
        }
    }
    if !distinct_depths(&rows) {
        return;
    }
    // Order independence: a shuffled and a reversed stream give the same bytes and pixel.
    let mut seed = input.u32().unwrap_or(0x9e37_79b9) | 1;
    let mut order: Vec<usize> = (0..n).collect();
    for i in (1..n).rev() {
        seed ^= seed << 13;
        seed ^= seed >> 17;
        seed ^= seed << 5;
        order.swap(i, seed as usize % (i + 1));
    }
    let reversed: Vec<usize> = (0..n).rev().collect();
    for order in [order, reversed] {
        let mut other = Hybrid::<K, A>::new();
        for &i in &order {
            other.insert(&frags[i]);
        }
        assert_eq!(
            other, ht,
            "K = {K} {name}: HT depends on submission order {order:?} of {rows:?}"
        );
        let (a, b) = (other.resolve(), ht.resolve());
        assert_eq!(a.transmittance.to_bits(), b.transmittance.to_bits());
        assert_eq!(
            a.color.to_array().map(f32::to_bits),
            b.color.to_array().map(f32::to_bits)
        );
    }
}

/// The integer RGBA8 resolve of HT (`check_hybrid_span` compares the kernel's with the
/// reference formula after every fragment): the reference against the exact composite of the
/// head and tail within the derived bound (`mlab_reference::resolve_int::ht_bound`), over
/// [`INT_BACKGROUNDS`].
fn check_ht_int_resolve<const K: usize, A: Model>(ht: &Hybrid<K, A>, rows: &[Row]) {
    for bg in INT_BACKGROUNDS {
        let (head, tail) = (ht.head().as_slice(), ht.tail());
        let got = mlab_reference::resolve_int::ht_rgba8(head, tail, bg);
        let exact = mlab_reference::resolve_int::ht_exact(head, tail, bg);
        let bound = mlab_reference::resolve_int::ht_bound(head, tail, bg);
        check_int_bound(got, exact, bound, || {
            format!("K = {K} {} integer HT resolve {bg:?} after {rows:?}", A::NAME)
        });
    }
}
