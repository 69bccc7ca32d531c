//! MLAB and HT through the kernel's 8-pixel lanes: the same images as [`super::kernel`], bit
//! for bit.

use super::{Arith, BinnedStream, Image};
use mlab::glam::Vec3;
use mlab::lanes::{self, HybridSpan, LANES, ResolvedLanes};
use mlab::{Arithmetic, Fragment, Paper, Row, Unbiased};

/// A kernel through its 8-pixel lanes: the frame is cut into spans of 8 pixels of a row;
/// consecutive fragments of the stream that fall in one span on distinct lanes are inserted
/// with one call (a rasterizer's span of a primitive), which keeps each pixel's submission
/// order. Fragments are quantized with `quantize` (the arithmetic's).
fn run_lanes<S: Clone>(
    binned: &BinnedStream,
    empty: S,
    quantize: fn(&Fragment) -> Row,
    insert: fn(&mut S, &[Row; LANES], u8),
    resolve: fn(&S) -> ResolvedLanes,
) -> Result<Image, String> {
    let s = binned.stream;
    let spans_x = (s.width as usize).div_ceil(LANES);
    let mut spans = vec![empty; spans_x * s.height as usize];
    let (mut cur, mut rows, mut mask) = (0usize, [Row::EMPTY; LANES], 0u8);
    for (i, f) in s.frags.iter().enumerate() {
        let row = quantize(&f.to_kernel().map_err(|e| format!("fragment {i}: {e}"))?);
        let (x, y) = ((f.pixel % s.width) as usize, (f.pixel / s.width) as usize);
        let (span, lane) = (y * spans_x + x / LANES, x % LANES);
        if mask != 0 && (span != cur || mask & (1 << lane) != 0) {
            insert(&mut spans[cur], &rows, mask);
            (rows, mask) = ([Row::EMPTY; LANES], 0);
        }
        cur = span;
        rows[lane] = row;
        mask |= 1 << lane;
    }
    if mask != 0 {
        insert(&mut spans[cur], &rows, mask);
    }
    let bg = Vec3::from(s.background);
    let mut rgb = Vec::with_capacity(s.pixels());
    let mut vis = Vec::with_capacity(s.pixels());
    for y in 0..s.height as usize {
        for sx in 0..spans_x {
            let r = resolve(&spans[y * spans_x + sx]);
            for lane in 0..LANES.min(s.width as usize - sx * LANES) {
                let p = r.get(lane).ok_or("lane out of range")?;
                rgb.push(p.over(bg).to_array());
                vis.push(p.transmittance);
            }
        }
    }
    Ok(Image {
        width: s.width,
        height: s.height,
        rgb,
        vis,
    })
}

fn mlab_lanes<A: Arithmetic>(m: usize, binned: &BinnedStream) -> Result<Image, String> {
    let q: fn(&Fragment) -> Row = A::quantize;
    match m {
        1 => run_lanes(
            binned,
            [[Row::EMPTY; LANES]; 1],
            q,
            lanes::mlab_insert_with::<A, 1>,
            lanes::mlab_resolve::<1>,
        ),
        2 => run_lanes(
            binned,
            [[Row::EMPTY; LANES]; 2],
            q,
            lanes::mlab_insert_with::<A, 2>,
            lanes::mlab_resolve::<2>,
        ),
        4 => run_lanes(
            binned,
            [[Row::EMPTY; LANES]; 4],
            q,
            lanes::mlab_insert_with::<A, 4>,
            lanes::mlab_resolve::<4>,
        ),
        8 => run_lanes(
            binned,
            [[Row::EMPTY; LANES]; 8],
            q,
            lanes::mlab_insert_with::<A, 8>,
            lanes::mlab_resolve::<8>,
        ),
        _ => Err(format!("MLAB {m} lanes: supported row counts are 1, 2, 4, 8")),
    }
}

fn hybrid_lanes<A: Arithmetic>(k: usize, binned: &BinnedStream) -> Result<Image, String> {
    let q: fn(&Fragment) -> Row = A::quantize;
    match k {
        0 => run_lanes(
            binned,
            HybridSpan::<0, A>::new(),
            q,
            lanes::hybrid_insert::<0, A>,
            lanes::hybrid_resolve::<0, A>,
        ),
        1 => run_lanes(
            binned,
            HybridSpan::<1, A>::new(),
            q,
            lanes::hybrid_insert::<1, A>,
            lanes::hybrid_resolve::<1, A>,
        ),
        3 => run_lanes(
            binned,
            HybridSpan::<3, A>::new(),
            q,
            lanes::hybrid_insert::<3, A>,
            lanes::hybrid_resolve::<3, A>,
        ),
        7 => run_lanes(
            binned,
            HybridSpan::<7, A>::new(),
            q,
            lanes::hybrid_insert::<7, A>,
            lanes::hybrid_resolve::<7, A>,
        ),
        _ => Err(format!("HT {k} lanes: supported head sizes are 0, 1, 3, 7")),
    }
}

/// MLAB `m` (1, 2, 4 or 8) with arithmetic `arith` through the kernel's 8-pixel lanes.
pub fn mlab_lanes_with(m: usize, arith: Arith, binned: &BinnedStream) -> Result<Image, String> {
    match arith {
        Arith::Paper => mlab_lanes::<Paper>(m, binned),
        Arith::Unbiased => mlab_lanes::<Unbiased>(m, binned),
    }
}

/// HT `k` (0, 1, 3 or 7) with arithmetic `arith` through the kernel's 8-pixel lanes.
pub fn hybrid_lanes_with(k: usize, arith: Arith, binned: &BinnedStream) -> Result<Image, String> {
    match arith {
        Arith::Paper => hybrid_lanes::<Paper>(k, binned),
        Arith::Unbiased => hybrid_lanes::<Unbiased>(k, binned),
    }
}
