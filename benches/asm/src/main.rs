//! Every hot entry point of the kernel, each in a symbol of its own (`#[inline(never)]`
//! wrappers, v0 mangling names the generic arguments), run once on a small stream so that
//! nothing is optimised away. `benches/asm/check.sh` disassembles this binary and fails on
//! instructions that AMD CPUs microcode (masked stores, gathers, scatters, compress to
//! memory) in the wrappers and every function of the kernel they call.

use mlab::lanes::{self, FragmentLanes, HybridSpan, LANES};
use mlab::{
    Arithmetic, Background, DynFramebuffer, Fragment, Framebuffer, HybridFramebuffer, Layers, MlabFramebuffer, Paper,
    Row, SpanBatcher, Unbiased,
};
use std::hint::black_box;

const W: u32 = 24;
const H: u32 = 4;

/// A deterministic stream of fragments for pixels of a `W x H` frame.
fn stream() -> Vec<(u32, u32, Fragment)> {
    let mut s = 0x9e37_79b9_u32;
    let mut next = move || {
        s ^= s << 13;
        s ^= s >> 17;
        s ^= s << 5;
        s
    };
    (0..400)
        .map(|_| {
            let (x, y) = (next() % W, next() % H);
            let c = |v: u32| (v % 1000) as f32 / 1000.0;
            let f = Fragment::straight_rgba([c(next()), c(next()), c(next()), c(next())], c(next()) * 10.0);
            (x, y, f.expect("valid"))
        })
        .collect()
}

#[inline(never)]
fn lanes_mlab<A: Arithmetic, const M: usize>(rows: &[[Row; LANES]]) -> [[Row; LANES]; M] {
    let mut span = [[Row::EMPTY; LANES]; M];
    for (i, r) in rows.iter().enumerate() {
        lanes::mlab_insert_with::<A, M>(&mut span, r, if i % 3 == 0 { 0xff } else { 0x5a });
    }
    span
}

#[inline(never)]
fn lanes_hybrid<A: Arithmetic, const K: usize>(rows: &[[Row; LANES]]) -> HybridSpan<K, A> {
    let mut span = HybridSpan::<K, A>::default();
    for (i, r) in rows.iter().enumerate() {
        lanes::hybrid_insert(&mut span, r, if i % 3 == 0 { 0xff } else { 0xa5 });
    }
    span
}

/// Per-pixel, span and batched inserts and every resolve of one framebuffer.
#[inline(never)]
fn framebuffer<F: Framebuffer>(fb: &mut F, frags: &[(u32, u32, Fragment)]) -> u64 {
    let mut sum = 0u64;
    for (x, y, f) in frags {
        sum += u64::from(fb.insert(*x, *y, f).is_ok());
    }
    let lanes = FragmentLanes {
        color: [[0.25; LANES], [0.5; LANES], [0.75; LANES]],
        alpha: [0.5; LANES],
        depth: [1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0],
        key: Some([11, 12, 13, 14, 15, 16, 17, 18]),
    };
    for y in 0..H {
        sum += u64::from(fb.insert_span_fragments(8, y, &lanes, 0xf3).map_or(0, |i| i.0));
        sum += u64::from(fb.insert_span_straight(0, y, &lanes, 0xff).map_or(0, |i| i.0));
    }
    {
        let mut batch = SpanBatcher::new(&mut *fb);
        for (x, y, f) in frags {
            sum += u64::from(batch.insert(*x, *y, f).is_ok());
        }
        sum += u64::from(batch.finish().is_ok());
    }
    let n = (W * H) as usize;
    let bg = Background::Opaque(mlab::glam::Vec3::splat(0.5));
    let mut rgba8 = vec![[0u8; 4]; n];
    let mut f32s = vec![mlab::glam::Vec4::ZERO; n];
    let mut f16s = vec![[mlab::half::f16::ZERO; 4]; n];
    for b in [bg, Background::Transparent] {
        sum += u64::from(fb.resolve_rgba8(&mut rgba8, b).is_ok());
        sum += u64::from(fb.resolve_into(&mut f32s, b).is_ok());
        sum += u64::from(fb.resolve_rgba16f(&mut f16s, b).is_ok());
        sum += u64::from(fb.resolve_span_rgba8(1, 1, b)[3][0]);
    }
    sum + rgba8.iter().map(|p| u64::from(p[0])).sum::<u64>()
}

fn dynamic<A: Arithmetic>(frags: &[(u32, u32, Fragment)]) -> u64 {
    let mut sum = 0;
    for n in Layers::SIZES {
        for layers in [Layers::Mlab(n), Layers::Hybrid(n)] {
            let mut storage = vec![Row::EMPTY; layers.rows_needed(W, H).expect("size")];
            let mut fb = DynFramebuffer::<A>::new_cleared(layers, &mut storage, W, H).expect("fb");
            sum += framebuffer(&mut fb, frags);
        }
    }
    sum
}

macro_rules! pixel_major {
    ($frags:expr, $sum:ident, $($ty:ident<$n:literal, $a:ty>),*) => {$(
        let mut storage = vec![Row::EMPTY; $ty::<$n, $a>::rows_needed(W, H).expect("size")];
        let mut fb = $ty::<$n, $a>::new_cleared(&mut storage, W, H).expect("fb");
        $sum += framebuffer(&mut fb, $frags);
    )*};
}

macro_rules! each_size {
    ($f:ident, $rows:expr, $sum:ident, $($n:literal)*) => {$(
        $sum += u64::from(black_box($f::<Unbiased, $n>($rows)) != black_box($f::<Unbiased, $n>(&[])));
        $sum += u64::from(black_box($f::<Paper, $n>($rows)) != black_box($f::<Paper, $n>(&[])));
    )*};
}

#[cfg(feature = "plant")]
#[inline(never)]
fn planted(slots: &mut [wide::f64x4], x: wide::f64x4) {
    // A select stored where its second operand was loaded from: LLVM emits vmaskmovpd on AVX.
    for s in slots.iter_mut() {
        *s = x.simd_le(*s).select(x, *s);
    }
}

fn main() {
    let frags = black_box(stream());
    let rows: Vec<[Row; LANES]> = frags
        .chunks(LANES)
        .filter_map(|c| <&[_; LANES]>::try_from(c).ok())
        .map(|c| c.map(|(_, _, f)| Unbiased::quantize(&f, f.hash(0))))
        .collect();
    let rows = black_box(&rows[..]);
    let mut sum = 0u64;
    each_size!(lanes_mlab, rows, sum, 1 2 3 4 5 6 7 8);
    each_size!(lanes_hybrid, rows, sum, 1 2 3 4 5 6 7 8);
    sum += dynamic::<Unbiased>(&frags) + dynamic::<Paper>(&frags);
    pixel_major!(&frags, sum, MlabFramebuffer<1, Unbiased>, MlabFramebuffer<4, Unbiased>, MlabFramebuffer<8, Paper>);
    pixel_major!(&frags, sum, HybridFramebuffer<1, Unbiased>, HybridFramebuffer<3, Unbiased>, HybridFramebuffer<8, Paper>);
    #[cfg(feature = "plant")]
    {
        let mut slots = black_box(vec![wide::f64x4::splat(2.0); 64]);
        planted(&mut slots, black_box(wide::f64x4::splat(1.0)));
        sum += slots.iter().map(|s| s.to_array()[0] as u64).sum::<u64>();
    }
    println!("mlab-asm: {sum}");
}
