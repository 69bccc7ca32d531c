//! Properties that pin the paper's claims (issue: kernel, section 8).
//!
//! Every property runs in both arithmetics, against the exact oracle of `mlab-reference`.
//! Quantization bounds used below (DELTA = 0.5/255 + 1e-6 for the paper's rounding,
//! 1/255 + 1e-6 for the unbiased one: `mlab_reference::Model::DELTA`; n fragments, per
//! channel):
//! - M >= n: `DELTA * sum_j (1 + C_behind_j)` (see `mlab_reference::oracle_with_bound`), at most
//!   `2 n DELTA` for normal fragments over a background in [0, 1].
//! - M = 1, stream sorted front to back or back to front: `4 n DELTA`. Each step adds at
//!   most DELTA from each of: color quantization, transmittance quantization, the color
//!   product rounding and the transmittance product rounding; the transmittance error is
//!   damped by later coverage (`(1 - t) u_k <= u_k - u_(k+1) + 2 DELTA` telescopes).
//! - Background visibility: each merge rounds one product, moving the visibility by at
//!   most 0.5/255; so two submission orders differ by at most `n / 255` (plus f32 slack).

mod common;

use common::*;
use mlab::glam::Vec3;
use mlab::{BlendingArray, Fragment, Hybrid, Paper, Row, TailFormat, Unbiased, mlab as listing1};
use mlab_reference::{Model, oracle, oracle_with_bound};
use proptest::prelude::*;

const BG: [f64; 3] = [0.25, 0.5, 1.0];

fn bg() -> Vec3 {
    Vec3::new(BG[0] as f32, BG[1] as f32, BG[2] as f32)
}

fn run_mlab<const M: usize, A: Model>(stream: &[Fragment]) -> BlendingArray<M, A> {
    let mut b = BlendingArray::<M, A>::new();
    for f in stream {
        b.insert(f);
    }
    b
}

fn run_hybrid<const K: usize, A: Model>(stream: &[Fragment]) -> Hybrid<K, A> {
    let mut h = Hybrid::<K, A>::new();
    for f in stream {
        h.insert(f);
    }
    h
}

fn pixel(c: Vec3) -> [f64; 3] {
    c.to_array().map(|x| x as f64)
}

/// Property 1 for one M: streams of at most M fragments match the oracle within the bound.
fn mlab_fits_matches_oracle<const M: usize, A: Model>(stream: &[Fragment]) -> Result<(), TestCaseError> {
    prop_assume!(stream.len() <= M);
    let got = pixel(run_mlab::<M, A>(stream).resolve().over(bg()));
    let (want, _, bound) = oracle_with_bound(stream, BG, A::DELTA);
    for ch in 0..3 {
        prop_assert!(
            (got[ch] - want[ch]).abs() <= bound[ch],
            "{} M={M} channel {ch}: got {got:?} want {want:?} bound {bound:?}",
            A::NAME
        );
    }
    Ok(())
}

fn p1<A: Model>(stream: &[Fragment]) -> Result<(), TestCaseError> {
    mlab_fits_matches_oracle::<1, A>(&stream[..stream.len().min(1)])?;
    mlab_fits_matches_oracle::<2, A>(&stream[..stream.len().min(2)])?;
    mlab_fits_matches_oracle::<4, A>(&stream[..stream.len().min(4)])?;
    mlab_fits_matches_oracle::<8, A>(stream)
}

fn p1_hybrid<A: Model>(stream: &[Fragment]) -> Result<(), TestCaseError> {
    let h = run_hybrid::<7, A>(stream);
    prop_assert_eq!(h.tail().count(), 0);
    let got = pixel(h.resolve().over(bg()));
    let (want, _, bound) = oracle_with_bound(stream, BG, A::DELTA);
    for ch in 0..3 {
        prop_assert!((got[ch] - want[ch]).abs() <= bound[ch], "{}", A::NAME);
    }
    Ok(())
}

fn p2<A: Model>(stream: &[Fragment]) -> Result<(), TestCaseError> {
    let got = pixel(run_mlab::<1, A>(stream).resolve().over(bg()));
    let (want, _) = oracle(stream, BG);
    let bound = 4.0 * stream.len() as f64 * A::DELTA;
    prop_assert!(
        max_diff(got, want) <= bound,
        "{}: got {:?} want {:?} bound {}",
        A::NAME,
        got,
        want,
        bound
    );
    Ok(())
}

fn p3<A: Model>(stream: &[Fragment]) -> Result<(), TestCaseError> {
    let f = &stream[mlab_reference::oracle::order(stream)[0]];
    let nearest = A::quantize(f, f.hash(0));
    let want = [nearest.color()[0], nearest.color()[1], nearest.color()[2], 255];
    let px = |r: mlab::Resolved| mlab::to_rgba8(r.over(bg()).extend(1.0));
    prop_assert_eq!(px(run_mlab::<1, A>(stream).resolve()), want);
    prop_assert_eq!(px(run_mlab::<2, A>(stream).resolve()), want);
    prop_assert_eq!(px(run_mlab::<3, A>(stream).resolve()), want);
    prop_assert_eq!(px(run_mlab::<4, A>(stream).resolve()), want);
    prop_assert_eq!(px(run_mlab::<8, A>(stream).resolve()), want);
    prop_assert_eq!(px(run_hybrid::<1, A>(stream).resolve()), want);
    prop_assert_eq!(px(run_hybrid::<3, A>(stream).resolve()), want);
    Ok(())
}

/// Background visibility across orders: each merge rounds one product, moving the
/// visibility by less than `delta` (up to f32 slack), so two orders differ by at most
/// `2 n delta`, and each stays within `n delta` of the product of the quantized
/// transmittances.
fn p4<A: Model>(stream: &[Fragment], shuffled: &[Fragment]) -> Result<(), TestCaseError> {
    let half = stream.len() as f64 * (A::DELTA - 1e-6) + 1e-5;
    let v = |s: &[Fragment], m: usize| -> f64 {
        (match m {
            1 => visibility_bytes_product(run_mlab::<1, A>(s).rows()),
            _ => visibility_bytes_product(run_mlab::<4, A>(s).rows()),
        }) as f64
    };
    for m in [1, 4] {
        let (v1, v2) = (v(stream, m), v(shuffled, m));
        prop_assert!((v1 - v2).abs() <= 2.0 * half, "{} M={}: {} vs {}", A::NAME, m, v1, v2);
    }
    let exact: f64 = stream
        .iter()
        .map(|f| A::quantize(f, f.hash(0)).transmittance() as f64 / 255.0)
        .product();
    prop_assert!((v(stream, 4) - exact).abs() <= half, "{}", A::NAME);
    Ok(())
}

fn p5<A: Model>(stream: &[Fragment], shuffled: &[Fragment]) -> Result<(), TestCaseError> {
    prop_assert_eq!(run_hybrid::<1, A>(stream), run_hybrid::<1, A>(shuffled));
    prop_assert_eq!(run_hybrid::<3, A>(stream), run_hybrid::<3, A>(shuffled));
    prop_assert_eq!(run_hybrid::<7, A>(stream), run_hybrid::<7, A>(shuffled));
    let (a, b) = (
        run_hybrid::<3, A>(stream).resolve(),
        run_hybrid::<3, A>(shuffled).resolve(),
    );
    prop_assert_eq!(a.transmittance.to_bits(), b.transmittance.to_bits());
    prop_assert_eq!(
        a.color.to_array().map(f32::to_bits),
        b.color.to_array().map(f32::to_bits)
    );
    Ok(())
}

fn p6<A: Model>(stream: &[Fragment], additive: &[Fragment]) -> Result<(), TestCaseError> {
    let mut b1 = BlendingArray::<1, A>::new();
    let mut b3 = BlendingArray::<3, A>::new();
    let mut b8 = BlendingArray::<8, A>::new();
    let mut h3 = Hybrid::<3, A>::new();
    for f in stream {
        b1.insert(f);
        b3.insert(f);
        b8.insert(f);
        h3.insert(f);
        for rows in [&b1.rows()[..], &b3.rows()[..], &b8.rows()[..], &h3.head()[..]] {
            check_invariants(rows, true).map_err(TestCaseError::fail)?;
        }
    }
    // Additive light may exceed coverage; the ordering invariants still hold.
    for f in additive {
        b3.insert(f);
        h3.insert(f);
        check_invariants(b3.rows(), false).map_err(TestCaseError::fail)?;
        check_invariants(h3.head(), false).map_err(TestCaseError::fail)?;
    }
    Ok(())
}

fn p7<A: Model>(stream: &[Fragment]) -> Result<(), TestCaseError> {
    let got = pixel(run_mlab::<8, A>(stream).resolve().over(bg()));
    let (want, _, bound) = oracle_with_bound(stream, BG, A::DELTA);
    for ch in 0..3 {
        prop_assert!(
            (got[ch] - want[ch]).abs() <= bound[ch],
            "{}: got {:?} want {:?}",
            A::NAME,
            got,
            want
        );
    }
    Ok(())
}

/// The stream in submission order sorted front to back or back to front. Ties (equal
/// depths, `-0.0 == 0.0`) composite later-in-front, like OVER, so tied fragments can only be
/// submitted back to front: front to back keeps the first fragment of each depth only.
fn sorted(mut stream: Vec<Fragment>, front_to_back: bool) -> Vec<Fragment> {
    stream.sort_by(|a, b| a.depth().partial_cmp(&b.depth()).expect("finite"));
    if front_to_back {
        stream.dedup_by(|b, a| a.depth() == b.depth());
    } else {
        stream.reverse();
    }
    stream
}

fn visibility_bytes_product(rows: &[Row]) -> f32 {
    mlab::resolve_rows(rows).transmittance
}

proptest! {
    /// 1. M >= number of fragments: MLAB equals the oracle within the quantization bound.
    #[test]
    fn p1_mlab_with_enough_rows_matches_oracle(stream in prop::collection::vec(normal_fragment(), 0..=8)) {
        p1::<Paper>(&stream)?;
        p1::<Unbiased>(&stream)?;
    }

    /// 1 (HT). K >= number of fragments: the tail stays empty and HT equals the oracle too.
    #[test]
    fn p1_hybrid_with_enough_head_rows_matches_oracle(stream in prop::collection::vec(normal_fragment(), 0..=7)) {
        p1_hybrid::<Paper>(&stream)?;
        p1_hybrid::<Unbiased>(&stream)?;
    }

    /// 2. Sorted streams (either direction): MLAB with one row equals the oracle within 4 n DELTA
    /// (paper 4.1: "any number of fragments ... with just one entry").
    #[test]
    fn p2_one_row_composites_sorted_streams(
        stream in prop::collection::vec(normal_fragment(), 0..=40),
        front_to_back in any::<bool>(),
    ) {
        let stream = sorted(stream, front_to_back);
        p2::<Paper>(&stream)?;
        p2::<Unbiased>(&stream)?;
    }

    /// 3. Fully opaque fragments: the pixel is the nearest fragment's color, exactly, for every
    /// M (and for HT with K >= 1). Nearest = smallest depth, later submission on ties.
    #[test]
    fn p3_opaque_gives_nearest_color(
        stream in prop::collection::vec((prop::array::uniform3(0.0f32..=1.0), depth()), 1..=20),
    ) {
        let stream: Vec<Fragment> = stream.into_iter().map(|(c, z)| straight(c, 1.0, z)).collect();
        p3::<Paper>(&stream)?;
        p3::<Unbiased>(&stream)?;
    }

    /// 4. Background visibility does not depend on submission order: MLAB within n/255
    /// (each merge rounds one product); HT exactly, for distinct depths.
    #[test]
    fn p4_visibility_is_order_independent(
        stream in prop::collection::vec(normal_fragment(), 0..=24),
        seed in any::<u64>(),
    ) {
        let mut shuffled = stream.clone();
        shuffle(&mut shuffled, seed);
        p4::<Paper>(&stream, &shuffled)?;
        p4::<Unbiased>(&stream, &shuffled)?;
    }

    /// 4 (HT) and 5. HT is bit-identical under any permutation of a stream with distinct depths.
    #[test]
    fn p5_hybrid_is_permutation_invariant(
        stream in prop::collection::vec((prop::array::uniform3(0.0f32..=1.0), alpha(), any::<bool>()), 0..=40),
        seed in any::<u64>(),
    ) {
        // Distinct depths: the index, offset to include negatives.
        let stream: Vec<Fragment> = stream
            .into_iter()
            .enumerate()
            .map(|(i, (c, a, additive))| {
                let z = i as f32 * 0.37 - 3.0;
                if additive {
                    Fragment::additive(Vec3::from_array(c), z).expect("valid")
                } else {
                    straight(c, a, z)
                }
            })
            .collect();
        let mut shuffled = stream.clone();
        shuffle(&mut shuffled, seed);
        p5::<Paper>(&stream, &shuffled)?;
        p5::<Unbiased>(&stream, &shuffled)?;
    }

    /// 6. After any stream: rows sorted, empty rows only at the back, color within coverage.
    #[test]
    fn p6_invariants_hold_after_every_insert(
        stream in prop::collection::vec(normal_fragment(), 0..=40),
        additive in prop::collection::vec(additive_fragment(), 0..=4),
    ) {
        p6::<Paper>(&stream, &additive)?;
        p6::<Unbiased>(&stream, &additive)?;
    }

    /// 7. Additive fragments add their light (within rounding) in front of or behind others.
    #[test]
    fn p7_additive_light_is_added(
        normal in prop::collection::vec(normal_fragment(), 0..=5),
        additive in prop::collection::vec(additive_fragment(), 1..=3),
        seed in any::<u64>(),
    ) {
        let mut stream = normal;
        stream.extend(additive);
        shuffle(&mut stream, seed);
        p7::<Paper>(&stream)?;
        p7::<Unbiased>(&stream)?;
    }
}

/// Fisher-Yates with a small xorshift generator (deterministic from the seed).
fn shuffle<T>(v: &mut [T], seed: u64) {
    let mut s = seed | 1;
    for i in (1..v.len()).rev() {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        v.swap(i, (s % (i as u64 + 1)) as usize);
    }
}

/// 7, worked by hand: light 0.2 behind a half-transparent red and in front of it, with one
/// row (so the merge itself must carry the light).
#[test]
fn p7_additive_light_survives_the_merge() {
    let red = straight([1.0, 0.0, 0.0], 0.5, 1.0);
    let light_behind = Fragment::additive(Vec3::new(0.0, 0.2, 0.0), 2.0).unwrap();
    let light_front = Fragment::additive(Vec3::new(0.0, 0.2, 0.0), 0.5).unwrap();
    for order in [[red, light_behind], [light_behind, red]] {
        let c = run_mlab::<1, Paper>(&order).resolve().over(Vec3::ZERO);
        // 0.5 red, light 0.2 seen through T = 127/255.
        let want = Vec3::new(128.0 / 255.0, 51.0 * 127.0 / 255.0 / 255.0, 0.0);
        assert!((c - want).abs().max_element() <= 1.0 / 255.0, "{c:?} vs {want:?}");
    }
    for order in [[red, light_front], [light_front, red]] {
        let c = run_mlab::<1, Paper>(&order).resolve().over(Vec3::ZERO);
        let want = Vec3::new(128.0 / 255.0, 51.0 / 255.0, 0.0);
        assert!((c - want).abs().max_element() <= 1.0 / 255.0, "{c:?} vs {want:?}");
    }
    // Into an HT tail: light is neither skipped (T = 255) nor lost (alpha sum 0).
    let mut h = Hybrid::<1, Paper>::new();
    h.insert(&red);
    h.insert(&light_behind);
    assert_eq!(h.tail().count(), 1);
    let c = h.resolve().over(Vec3::ZERO);
    assert!((c.y - 51.0 * 127.0 / 255.0 / 255.0).abs() <= 1.0 / 255.0, "{c:?}");
}

/// Listing 1 by hand: the merge of the last two rows when a third fragment arrives.
#[test]
fn listing1_merges_the_last_two_rows() {
    let mut rows = [Row::EMPTY; 2];
    let insert = listing1::insert_with::<Paper, 2>;
    insert(&mut rows, Row::new([10, 0, 0], 200, 3.0));
    insert(&mut rows, Row::new([0, 20, 0], 100, 1.0));
    assert_eq!(rows, [Row::new([0, 20, 0], 100, 1.0), Row::new([10, 0, 0], 200, 3.0)]);
    insert(&mut rows, Row::new([0, 0, 30], 50, 2.0));
    // B' = [z1, z2, z3]; merge rows z2 and z3: A = (0,0,30) + (10,0,0)*50/255, T = 50*200/255.
    assert_eq!(rows, [Row::new([0, 20, 0], 100, 1.0), Row::new([2, 0, 30], 39, 2.0)]);
    // Equal depth goes in front (coplanar fragments blend like OVER in submission order).
    insert(&mut rows, Row::new([0, 0, 0], 0, 1.0));
    assert_eq!(rows[0], Row::new([0, 0, 0], 0, 1.0));
}
