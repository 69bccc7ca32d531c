//! Properties that pin the paper's claims (issue: kernel, section 8).
//!
//! Quantization bounds used below (DELTA = 0.5/255 + 1e-6, n fragments, per channel):
//! - M >= n: `DELTA * sum_j (1 + C_behind_j)` (see `common::oracle_with_bound`), at most
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
use mlab::{BlendingArray, Fragment, Hybrid, Row, mlab as listing1};
use proptest::prelude::*;

const BG: [f64; 3] = [0.25, 0.5, 1.0];

fn bg() -> Vec3 {
    Vec3::new(BG[0] as f32, BG[1] as f32, BG[2] as f32)
}

fn run_mlab<const M: usize>(stream: &[Fragment]) -> BlendingArray<M> {
    let mut b = BlendingArray::<M>::new();
    for f in stream {
        b.insert(f);
    }
    b
}

fn run_hybrid<const K: usize>(stream: &[Fragment]) -> Hybrid<K> {
    let mut h = Hybrid::<K>::new();
    for f in stream {
        h.insert(f);
    }
    h
}

fn pixel(c: Vec3) -> [f64; 3] {
    c.to_array().map(|x| x as f64)
}

/// Property 1 for one M: streams of at most M fragments match the oracle within the bound.
fn mlab_fits_matches_oracle<const M: usize>(stream: &[Fragment]) -> Result<(), TestCaseError> {
    prop_assume!(stream.len() <= M);
    let got = pixel(run_mlab::<M>(stream).resolve().over(bg()));
    let (want, _, bound) = oracle_with_bound(stream, BG);
    for ch in 0..3 {
        prop_assert!(
            (got[ch] - want[ch]).abs() <= bound[ch],
            "M={M} channel {ch}: got {got:?} want {want:?} bound {bound:?}"
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
        mlab_fits_matches_oracle::<1>(&stream[..stream.len().min(1)])?;
        mlab_fits_matches_oracle::<2>(&stream[..stream.len().min(2)])?;
        mlab_fits_matches_oracle::<4>(&stream[..stream.len().min(4)])?;
        mlab_fits_matches_oracle::<8>(&stream)?;
    }

    /// 1 (HT). K >= number of fragments: the tail stays empty and HT equals the oracle too.
    #[test]
    fn p1_hybrid_with_enough_head_rows_matches_oracle(stream in prop::collection::vec(normal_fragment(), 0..=7)) {
        let h = run_hybrid::<7>(&stream);
        prop_assert_eq!(h.tail().count(), 0);
        let got = pixel(h.resolve().over(bg()));
        let (want, _, bound) = oracle_with_bound(&stream, BG);
        for ch in 0..3 {
            prop_assert!((got[ch] - want[ch]).abs() <= bound[ch]);
        }
    }

    /// 2. Sorted streams (either direction): MLAB with one row equals the oracle within 4 n DELTA
    /// (paper 4.1: "any number of fragments ... with just one entry").
    #[test]
    fn p2_one_row_composites_sorted_streams(
        stream in prop::collection::vec(normal_fragment(), 0..=40),
        front_to_back in any::<bool>(),
    ) {
        let stream = sorted(stream, front_to_back);
        let got = pixel(run_mlab::<1>(&stream).resolve().over(bg()));
        let (want, _) = oracle(&stream, BG);
        let bound = 4.0 * stream.len() as f64 * DELTA;
        prop_assert!(max_diff(got, want) <= bound, "got {:?} want {:?} bound {}", got, want, bound);
    }

    /// 3. Fully opaque fragments: the pixel is the nearest fragment's color, exactly, for every
    /// M (and for HT with K >= 1). Nearest = smallest depth, later submission on ties.
    #[test]
    fn p3_opaque_gives_nearest_color(
        stream in prop::collection::vec((prop::array::uniform3(0.0f32..=1.0), depth()), 1..=20),
    ) {
        let stream: Vec<Fragment> = stream.into_iter().map(|(c, z)| straight(c, 1.0, z)).collect();
        let nearest = stream[oracle_order(&stream)[0]].row();
        let want = [nearest.color()[0], nearest.color()[1], nearest.color()[2], 255];
        let px = |r: mlab::Resolved| mlab::to_rgba8(r.over(bg()).extend(1.0));
        prop_assert_eq!(px(run_mlab::<1>(&stream).resolve()), want);
        prop_assert_eq!(px(run_mlab::<2>(&stream).resolve()), want);
        prop_assert_eq!(px(run_mlab::<3>(&stream).resolve()), want);
        prop_assert_eq!(px(run_mlab::<4>(&stream).resolve()), want);
        prop_assert_eq!(px(run_mlab::<8>(&stream).resolve()), want);
        prop_assert_eq!(px(run_hybrid::<1>(&stream).resolve()), want);
        prop_assert_eq!(px(run_hybrid::<3>(&stream).resolve()), want);
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
        let bound = stream.len() as f64 / 255.0 + 1e-5;
        let v1 = visibility_bytes_product(run_mlab::<1>(&stream).rows()) as f64;
        let v2 = visibility_bytes_product(run_mlab::<1>(&shuffled).rows()) as f64;
        prop_assert!((v1 - v2).abs() <= bound, "M=1: {} vs {}", v1, v2);
        let v1 = visibility_bytes_product(run_mlab::<4>(&stream).rows()) as f64;
        let v2 = visibility_bytes_product(run_mlab::<4>(&shuffled).rows()) as f64;
        prop_assert!((v1 - v2).abs() <= bound, "M=4: {} vs {}", v1, v2);
        // And both stay within n/(2*255) of the product of the quantized transmittances.
        let exact: f64 = stream.iter().map(|f| f.row().transmittance() as f64 / 255.0).product();
        prop_assert!((v1 - exact).abs() <= bound / 2.0 + 1e-5);
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
        prop_assert_eq!(run_hybrid::<1>(&stream), run_hybrid::<1>(&shuffled));
        prop_assert_eq!(run_hybrid::<3>(&stream), run_hybrid::<3>(&shuffled));
        prop_assert_eq!(run_hybrid::<7>(&stream), run_hybrid::<7>(&shuffled));
        let (a, b) = (run_hybrid::<3>(&stream).resolve(), run_hybrid::<3>(&shuffled).resolve());
        prop_assert_eq!(a.transmittance.to_bits(), b.transmittance.to_bits());
        prop_assert_eq!(a.color.to_array().map(f32::to_bits), b.color.to_array().map(f32::to_bits));
    }

    /// 6. After any stream: rows sorted, empty rows only at the back, color within coverage.
    #[test]
    fn p6_invariants_hold_after_every_insert(
        stream in prop::collection::vec(normal_fragment(), 0..=40),
        additive in prop::collection::vec(additive_fragment(), 0..=4),
    ) {
        let mut b1 = BlendingArray::<1>::new();
        let mut b3 = BlendingArray::<3>::new();
        let mut b8 = BlendingArray::<8>::new();
        let mut h3 = Hybrid::<3>::new();
        for f in &stream {
            b1.insert(f);
            b3.insert(f);
            b8.insert(f);
            h3.insert(f);
            for rows in [&b1.rows()[..], &b3.rows()[..], &b8.rows()[..], &h3.head()[..]] {
                check_invariants(rows, true).map_err(TestCaseError::fail)?;
            }
        }
        // Additive light may exceed coverage; the ordering invariants still hold.
        for f in &additive {
            b3.insert(f);
            h3.insert(f);
            check_invariants(b3.rows(), false).map_err(TestCaseError::fail)?;
            check_invariants(h3.head(), false).map_err(TestCaseError::fail)?;
        }
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
        let got = pixel(run_mlab::<8>(&stream).resolve().over(bg()));
        let (want, _, bound) = oracle_with_bound(&stream, BG);
        for ch in 0..3 {
            prop_assert!((got[ch] - want[ch]).abs() <= bound[ch], "got {:?} want {:?}", got, want);
        }
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
        let c = run_mlab::<1>(&order).resolve().over(Vec3::ZERO);
        // 0.5 red, light 0.2 seen through T = 127/255.
        let want = Vec3::new(128.0 / 255.0, 51.0 * 127.0 / 255.0 / 255.0, 0.0);
        assert!((c - want).abs().max_element() <= 1.0 / 255.0, "{c:?} vs {want:?}");
    }
    for order in [[red, light_front], [light_front, red]] {
        let c = run_mlab::<1>(&order).resolve().over(Vec3::ZERO);
        let want = Vec3::new(128.0 / 255.0, 51.0 / 255.0, 0.0);
        assert!((c - want).abs().max_element() <= 1.0 / 255.0, "{c:?} vs {want:?}");
    }
    // Into an HT tail: light is neither skipped (T = 255) nor lost (alpha sum 0).
    let mut h = Hybrid::<1>::new();
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
    listing1::insert(&mut rows, Row::new([10, 0, 0], 200, 3.0));
    listing1::insert(&mut rows, Row::new([0, 20, 0], 100, 1.0));
    assert_eq!(rows, [Row::new([0, 20, 0], 100, 1.0), Row::new([10, 0, 0], 200, 3.0)]);
    listing1::insert(&mut rows, Row::new([0, 0, 30], 50, 2.0));
    // B' = [z1, z2, z3]; merge rows z2 and z3: A = (0,0,30) + (10,0,0)*50/255, T = 50*200/255.
    assert_eq!(rows, [Row::new([0, 20, 0], 100, 1.0), Row::new([2, 0, 30], 39, 2.0)]);
    // Equal depth goes in front (coplanar fragments blend like OVER in submission order).
    listing1::insert(&mut rows, Row::new([0, 0, 0], 0, 1.0));
    assert_eq!(rows[0], Row::new([0, 0, 0], 0, 1.0));
}
