//! The lab's catalog: the sizes it runs ([`MLAB_SIZES`], [`HT_SIZES`], [`KCLOSEST_SIZES`]),
//! the memory budgets of the tables ([`BUDGETS`]) and every command's list of methods, in
//! table order, in one place: the main job ([`main_job`]), `oit-lab faint` ([`faint`]),
//! `oit-lab stability` ([`stability`], [`stability_table`]), `oit-lab peers` ([`bounded`],
//! [`peers`], [`flicker`]) and `oit-lab evaluate`'s search ([`evaluate_candidates`]).

use super::{Arith, Method, MomentKind, Moments, Weight};

/// MLAB row counts the lab can run (const generics are instantiated for these).
pub const MLAB_SIZES: [usize; 10] = [1, 2, 3, 4, 5, 6, 7, 8, 12, 16];
/// HT head sizes the lab can run.
pub const HT_SIZES: [usize; 10] = [0, 1, 2, 3, 4, 5, 6, 7, 11, 15];

/// The K the lab runs (Diligent's tutorial offers a run-time choice; these are issue 25's).
pub const KCLOSEST_SIZES: [usize; 3] = [2, 4, 8];

/// The memory budgets of the tables, B/px.
pub const BUDGETS: [usize; 4] = [8, 16, 32, 64];

/// The methods of the main job (`oit-lab run`, `oit-lab evaluate`), in table order. A lanes
/// variant of the kernel goes here as one more entry per size (for example
/// `Method::MlabLanes(m)` after `Method::Mlab(m)`).
pub fn main_job() -> Vec<Method> {
    let mut v = vec![Method::Over, Method::Under];
    for m in [1, 2, 4, 8] {
        v.push(Method::Mlab(m));
    }
    for m in [1, 2, 4, 8] {
        v.push(Method::Hybrid(m - 1));
    }
    v.push(Method::MlabLanes(4));
    v.push(Method::HybridLanes(3));
    v.push(Method::MlabSorted(1));
    v.push(Method::MlabSorted(4));
    for n in [2, 4, 8] {
        v.push(Method::Adaptive(n));
    }
    v.extend(Weight::ALL.map(Method::Wboit));
    v.push(Method::BavoilMyers);
    v.push(Method::Meshkin);
    // Issue 25's peers, one each (every variant is in `oit-lab peers`): K-closest with 4
    // layers (20 B/px) and the paper's 6 power moments at 16 bit (112 bits + the RGBA16F
    // target, 22 B/px).
    v.push(Method::KClosest(4));
    v.push(Method::Mboit(Moments::new(MomentKind::Power6, true)));
    v
}

/// The methods of `oit-lab faint`, by memory: unsorted OVER (8 B), then for `M` = 1, 2, 4, 8 MLAB
/// `M` and HT `K = M - 1` (both `8 M` bytes per pixel), each with the paper's arithmetic and
/// the unbiased one.
pub fn faint() -> Vec<Method> {
    let mut v = vec![Method::Over];
    for m in [1usize, 2, 4, 8] {
        for a in Arith::ALL {
            v.push(Method::MlabWith(m, a));
        }
        for a in Arith::ALL {
            v.push(Method::HybridWith(m - 1, a));
        }
    }
    v
}

/// The methods of a stability run: the A-buffer itself (its change between orders is 0 unless
/// two fragments of a pixel share a depth), unsorted OVER, MLAB at every row count the lab
/// has, HT at every head size, AT 4, WBOIT eq. 7 and Meshkin.
pub fn stability() -> Vec<Method> {
    let mut v = vec![Method::Reference, Method::Over];
    v.extend(MLAB_SIZES.map(Method::Mlab));
    v.extend(HT_SIZES.map(Method::Hybrid));
    v.push(Method::Adaptive(4));
    v.push(Method::Wboit(Weight::Eq7));
    v.push(Method::Meshkin);
    v
}

/// The methods of `oit-lab stability`'s printed table (the others are in the recommendation).
pub fn stability_table() -> Vec<Method> {
    let mut v = vec![Method::Reference, Method::Over];
    v.extend([1, 2, 4, 8, 16].map(Method::Mlab));
    v.extend([0, 1, 3, 7].map(Method::Hybrid));
    v.push(Method::Adaptive(4));
    v.push(Method::Wboit(Weight::Eq7));
    v.push(Method::Meshkin);
    v
}

/// The bounded-memory methods (memory that does not grow with the fragments), in table order.
pub fn bounded() -> Vec<Method> {
    let mut v = vec![Method::Over];
    v.extend([1, 2, 3, 4, 8].map(Method::Mlab));
    v.extend([0, 1, 3, 7].map(Method::Hybrid));
    v.extend(KCLOSEST_SIZES.map(Method::KClosest));
    v.extend(Moments::ALL.map(Method::Mboit));
    v.extend(Weight::ALL.map(Method::Wboit));
    v.push(Method::BavoilMyers);
    v.push(Method::Meshkin);
    v
}

/// The methods of `oit-lab peers`: the A-buffer, the bounded ones, AT 4 (which stores every
/// fragment, as the A-buffer does), and MLAB 4 with f32 rows (the ceiling of MLAB 4's 8-byte
/// rows: 20 bytes a row, not a candidate of any budget).
pub fn peers() -> Vec<Method> {
    let mut v = vec![Method::Reference];
    v.extend(bounded());
    v.push(Method::Adaptive(4));
    v.push(Method::MlabF32(4));
    v
}

/// The methods whose camera-motion flicker `oit-lab peers` measures.
pub fn flicker() -> Vec<Method> {
    let mut v = vec![Method::Reference, Method::Over];
    v.extend([2, 4, 8].map(Method::Mlab));
    v.extend([1, 3].map(Method::Hybrid));
    v.extend(KCLOSEST_SIZES.map(Method::KClosest));
    v.extend(Moments::ALL.map(Method::Mboit));
    v.push(Method::Wboit(Weight::Eq7));
    v.push(Method::Adaptive(4));
    // MLAB 4 with the paper's rounding (no dither): how much of MLAB's flicker is the
    // default arithmetic's dithered merge.
    v.push(Method::MlabWith(4, Arith::Paper));
    v
}

/// The candidates of `oit-lab evaluate`'s search: every [`bounded`] method, then MLAB and HT at
/// every size of [`MLAB_SIZES`] and [`HT_SIZES`] that is not among them.
pub fn evaluate_candidates() -> Vec<Method> {
    let mut candidates = bounded();
    for m in MLAB_SIZES
        .map(Method::Mlab)
        .into_iter()
        .chain(HT_SIZES.map(Method::Hybrid))
    {
        if !candidates.contains(&m) {
            candidates.push(m);
        }
    }
    candidates
}
