//! `mlab_stream`: a stream of fragments into a blending array of M rows, in both
//! arithmetics, against the defect model, the reference quantizations, a reference Listing 1,
//! the background visibility bound and the f64 oracle; the same stream through the lanes
//! kernel (8 pixels, masks) byte for byte (see the crate docs' table).

use mlab::lanes::{self, LANES};
use mlab::{BlendingArray, Paper, Row, Unbiased, mlab as mlab_mod};
use mlab_reference::lanes::{check_fragment_lanes, check_mlab_span};
use mlab_reference::model::{Model, RefMlab, ref_fragment_hash, ref_key};
use mlab_reference::oracle::{multilinear_bound, visibility_bound};

use super::{
    MAX_FRAGMENTS, MlabSpan, check_int_resolve, exact, in_both_arithmetics, lane_mask, lane_rows, lanes_ok, occluding,
    parts, to_pixel_major,
};
use crate::check::{check_close, check_invariants, check_resolved, validate};
use crate::input::{Input, RawFragment};

/// `mlab_stream`: M from the first byte (1, 2, 3, 4 or 8), then a stream of fragments; the
/// stream runs in both arithmetics.
pub fn mlab_stream(data: &[u8]) {
    in_both_arithmetics(data, mlab_stream_a::<Paper>, mlab_stream_a::<Unbiased>);
}

fn mlab_stream_a<A: Model>(sel: u8, mut input: Input) {
    match sel % 5 {
        0 => mlab_stream_m::<1, A>(&mut input),
        1 => mlab_stream_m::<2, A>(&mut input),
        2 => mlab_stream_m::<3, A>(&mut input),
        3 => mlab_stream_m::<4, A>(&mut input),
        _ => mlab_stream_m::<8, A>(&mut input),
    }
}

fn mlab_stream_m<const M: usize, A: Model>(input: &mut Input) {
    let name = A::NAME;
    let mut array = BlendingArray::<M, A>::new();
    let mut reference = RefMlab::new::<A>(M);
    // Lanes: 8 pixels; lane 0 gets every fragment (it must equal `array`), the others the
    // fragments their bit of `lane_mask(n)` selects; off lanes are handed a garbage row.
    let mut span: MlabSpan<M> = [[Row::EMPTY; LANES]; M];
    let mut lane_arrays = [[Row::EMPTY; M]; LANES];
    let mut raws = Vec::new();
    let mut accepted = Vec::new();
    // Exact background visibility: the product of (1 - alpha).
    let mut visibility = 1.0f64;
    // Quantization error of each accepted fragment, in steps.
    let mut quant = Vec::new();
    while accepted.len() < MAX_FRAGMENTS {
        let Some(raw) = input.raw_fragment() else { break };
        raws.push(raw);
        if raws.len() == LANES {
            fragment_lanes::<A>(&raws, lane_mask(accepted.len() + 7));
            raws.clear();
        }
        let Some(f) = validate(&raw) else { continue };
        // The reference row (equal to the kernel's quantization in `A`: checked by `validate`)
        // and hash, of pixel 0 (`BlendingArray::insert`).
        let row = A::ref_row(&f, 0);
        let h = ref_fragment_hash(ref_key(&f), 0);
        array.insert(&f);
        let mask = lane_mask(accepted.len());
        let rows8 = lane_rows(row, mask);
        lanes::mlab_insert_hashed::<A, _>(&mut span, &rows8, &[h; LANES], mask);
        for (lane, a) in lane_arrays.iter_mut().enumerate() {
            if mask >> lane & 1 == 1 {
                mlab_mod::insert_hashed::<A, _>(a, rows8[lane], h);
            }
        }
        assert_eq!(
            to_pixel_major(&span),
            lane_arrays,
            "M = {M} {name}: lanes differ from scalar, mask {mask:#010b}"
        );
        assert_eq!(&lane_arrays[0], array.rows());
        lanes_ok(check_mlab_span(&span, &lane_arrays));
        reference.insert(row, h);
        accepted.push(parts(&f));
        quant.push(A::quant_error(f.alpha()));
        visibility *= 1.0 - f64::from(f.alpha());
        let n = accepted.len();
        let rows = array.rows();
        assert_eq!(
            rows.as_slice(),
            reference.rows().as_slice(),
            "M = {M} {name}: differs from reference Listing 1 after {accepted:?}"
        );
        check_invariants(rows, &accepted);
        let filled = rows.iter().filter(|r| !r.is_empty()).count();
        assert_eq!(filled, n.min(M), "M = {M} {name}: {rows:?} after {n} fragments");
        let r = array.resolve();
        check_resolved(r, M as f32, &accepted);
        // Every insert into a full array merges: `n - M` merges so far.
        let bound = visibility_bound(&quant, n.saturating_sub(M), A::MERGE_ERROR);
        let err = (f64::from(r.transmittance) - visibility).abs();
        assert!(
            err <= bound,
            "M = {M} {name}: visibility {r:?} vs exact {visibility} (error {err} > {bound}) after {accepted:?}"
        );
    }
    let n = accepted.len();
    if n <= M && occluding(&accepted) {
        check_close(array.resolve(), exact(&accepted), multilinear_bound(&quant), &accepted);
    }
    check_int_resolve(array.rows(), &accepted);
}

/// The integer RGBA8 resolve of MLAB rows (`SpanFramebuffer::resolve_rgba8` and
/// `MlabFramebuffer::resolve_rgba8` of one 8-pixel span holding them in every lane) against
/// the reference formula byte for byte, and the reference against the exact composite of
/// the rows within the derived bound (`mlab_reference::resolve_int`), over a transparent,
/// The 8 raw fragments' `(color, alpha, depth)` as given, whatever constructor they were
/// drawn for, into [`check_fragment_lanes`] (both constructors, premultiplied and straight).
fn fragment_lanes<A: Model>(raws: &[RawFragment], mask: u8) {
    let raws: [([f32; 3], f32, f32); LANES] = core::array::from_fn(|l| (raws[l].color, raws[l].a, raws[l].z));
    lanes_ok(check_fragment_lanes::<A>(&raws, mask));
}
