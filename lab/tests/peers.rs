//! Moment-based OIT and K-closest layered OIT against hand-computed 1-3 fragment cases of
//! their source formulas (lab/src/methods/moments.rs and kclosest.rs cite the lines).

use oit_lab::methods::kclosest::{EMPTY, OPACITY_THRESHOLD, layer_depth, pack};
use oit_lab::methods::moments::{dequantize, features, offsets, quantize, warp};
mod common;

use common::{close, pixel, render};
use oit_lab::methods::{BinnedStream, Layers, Method, MomentState, Moments};

/// Every permutation of `0..n` (Heap's algorithm).
fn permutations(n: usize) -> Vec<Vec<usize>> {
    fn heap(k: usize, a: &mut Vec<usize>, out: &mut Vec<Vec<usize>>) {
        if k <= 1 {
            out.push(a.clone());
            return;
        }
        for i in 0..k {
            heap(k - 1, a, out);
            let j = if k.is_multiple_of(2) { i } else { 0 };
            a.swap(j, k - 1);
        }
    }
    let mut out = Vec::new();
    heap(n, &mut (0..n).collect(), &mut out);
    out
}

#[test]
fn kclosest_packs_24_bit_depth_over_8_bit_transmittance_truncated() {
    // uint(0.5 * 16777215) = 8388607, uint(0.5 * 255) = 127.
    assert_eq!(pack(0.5, 0.5), (8_388_607 << 8) | 127);
    assert_eq!(pack(2.0, -1.0), 0xFFFF_FF00);
    assert_eq!(layer_depth(pack(0.25, 1.0)), 4_194_303);
    assert_eq!(pack(0.0, 1.0), 255);
}

#[test]
fn kclosest_keeps_the_k_nearest_and_counts_the_rest_into_the_tail() {
    // K = 2; layers at depths 0.1 < 0.2 < 0.3 < 0.4 with T bytes 127, 191, 63, 127.
    let p = [
        pack(0.1, 127.0 / 255.0),
        pack(0.2, 191.0 / 255.0),
        pack(0.3, 63.0 / 255.0),
        pack(0.4, 127.0 / 255.0),
    ];
    let mut l = Layers::new(2);
    for i in [2, 0, 1] {
        l.insert(p[i]);
    }
    assert_eq!(&l.slots[..2], &[p[0], p[1]]);
    assert_eq!(
        (l.tail_count, l.tail_t),
        (1, 63),
        "the farthest went to the tail: 255 * 63/255"
    );
    l.insert(p[3]);
    // unorm8: 63 * 127 / 255 = 31.38 -> 31.
    assert_eq!((l.tail_count, l.tail_t), (2, 31));
    // An identical layer ends the insert and touches nothing.
    let before = l;
    l.insert(p[0]);
    assert_eq!(l, before);
    let (t0, t1) = (127.0f32 / 255.0, 191.0f32 / 255.0);
    let d = |x: f32| (x * 16_777_215.0) as u32;
    assert_eq!(l.transmittance(d(0.1)), 1.0, "nothing in front of the nearest");
    assert_eq!(l.transmittance(d(0.05)), 1.0);
    assert_eq!(l.transmittance(d(0.2)), t0);
    // Behind both layers: their product divided by the tail count (2).
    assert_eq!(l.transmittance(d(0.35)), t0 * t1 / 2.0);
    assert_eq!(l.background(), t0 * t1 * (31.0 / 255.0));
    // With a free slot the tail does not count.
    let mut one = Layers::new(2);
    one.insert(p[1]);
    assert_eq!(one.slots[1], EMPTY);
    assert_eq!(one.background(), t1);
    assert_eq!(one.transmittance(d(0.9)), t1);
}

#[test]
fn kclosest_is_exact_up_to_k_fragments_with_8_bit_transmittance() {
    // Two fragments, K = 2: C = c_front + T_front c_back + T_front T_back bg, T = floor(255 (1 - a)) / 255.
    let (red, blue, white) = ([0.4, 0.0, 0.0], [0.0, 0.0, 0.3], [1.0, 1.0, 1.0]);
    let s = pixel(&[(2.0, red, 0.5), (1.0, blue, 0.6)], white);
    let img = render(Method::KClosest(2), &s);
    let tq = |a: f32| ((1.0 - a) * 255.0).floor() / 255.0;
    let (tf, tb) = (tq(0.6), tq(0.5));
    let want = [0, 1, 2].map(|k| blue[k] + tf * red[k] + tf * tb * white[k]);
    close(img.rgb[0], want, 2e-3);
    assert_eq!(img.vis[0], tf * tb);
    // The same two fragments with K = 1: red goes to the tail; it is composited with T_front
    // divided by the tail count 1, and the background gets the tail's 8-bit product.
    let img = render(Method::KClosest(1), &s);
    close(img.rgb[0], want, 2e-3);
    // A fragment at or below the threshold is not stored but composited behind what is.
    let s = pixel(&[(1.0, blue, 0.6), (2.0, [0.2, 0.2, 0.0], OPACITY_THRESHOLD)], white);
    let img = render(Method::KClosest(2), &s);
    let want = [0, 1, 2].map(|k| blue[k] + tf * [0.2, 0.2, 0.0][k] + tf * white[k]);
    close(img.rgb[0], want, 2e-3);
}

#[test]
fn kclosest_does_not_depend_on_the_order() {
    let f = [
        (3.0, [0.1, 0.2, 0.3], 0.3),
        (1.5, [0.3, 0.1, 0.0], 0.5),
        (2.2, [0.0, 0.4, 0.1], 0.7),
        (4.1, [0.2, 0.2, 0.2], 0.25),
        (1.1, [0.05, 0.0, 0.3], 0.4),
    ];
    // Up to K fragments: the same image bit for bit in every one of the 120 orders.
    for k in [8, 4] {
        let n = k.min(f.len());
        let first = render(Method::KClosest(k), &pixel(&f[..n], [0.5, 0.6, 0.7]));
        for order in permutations(n) {
            let s = pixel(&order.iter().map(|&i| f[i]).collect::<Vec<_>>(), [0.5, 0.6, 0.7]);
            assert_eq!(render(Method::KClosest(k), &s), first, "K = {k}, order {order:?}");
        }
    }
    // More than K: the layers and the tail count are the same in every order (the tail's
    // 8-bit product may round differently).
    let nf = BinnedStream::new(&pixel(&f, [0.0; 3])).near_far;
    let packed = |i: usize| pack(oit_lab::methods::baselines::window_depth(f[i].0, nf), 1.0 - f[i].2);
    let mut first: Option<Layers> = None;
    for order in permutations(f.len()) {
        let mut l = Layers::new(2);
        for &i in &order {
            l.insert(packed(i));
        }
        let first = first.get_or_insert(l);
        assert_eq!((l.slots, l.tail_count), (first.slots, first.tail_count), "{order:?}");
    }
}

#[test]
fn mboit_first_pass_sums_absorbance_and_its_moments() {
    // Two fragments, 4 power moments in f32: b0 = A1 + A2, b_k = A1 z1^k + A2 z2^k.
    let m = Moments::ALL[1];
    assert_eq!(m.name(), "MBOIT 4 power 32-bit");
    let mut s = MomentState::default();
    s.add(m, -0.5, 0.6);
    s.add(m, 0.25, 0.8);
    let (a1, a2) = (-(0.6f32.ln()), -(0.8f32.ln()));
    assert!((s.b0 - (a1 + a2)).abs() < 1e-6);
    for k in 1..=4 {
        let want = a1 * (-0.5f32).powi(k) + a2 * 0.25f32.powi(k);
        assert!((s.b[k as usize - 1] - want).abs() < 1e-6, "b{k}");
    }
    // A fully transparent fragment adds nothing; an opaque one is clamped to absorbance 10.
    let before = s;
    s.add(m, 0.0, 1.0);
    assert_eq!(s, before);
    let mut o = MomentState::default();
    o.add(m, 0.0, 0.0);
    assert_eq!(o.b0, 10.0);
    // Trigonometric: the moments are (cos k phi, sin k phi), phi = (z + 1) (pi - 0.05 pi).
    let t = Moments::ALL[7];
    let f = features(t, 0.0);
    let phi = 0.95 * std::f32::consts::PI;
    for k in 0..3 {
        let a = (k + 1) as f32 * phi;
        assert!((f[2 * k] - a.cos()).abs() < 1e-5 && (f[2 * k + 1] - a.sin()).abs() < 1e-5);
    }
    // The depth warp maps near to -1 and far to 1, logarithmically.
    assert!((warp(1.0, (1.0, 100.0)) + 1.0).abs() < 1e-6);
    assert!((warp(100.0, (1.0, 100.0)) - 1.0).abs() < 1e-6);
    assert!(warp(10.0, (1.0, 100.0)).abs() < 1e-6);
}

#[test]
fn mboit_16_bit_quantization_is_invertible_and_fits_unorm16() {
    for m in [Moments::ALL[0], Moments::ALL[2]] {
        let off = offsets(m);
        for i in 0..=20 {
            let z = -1.0 + i as f32 / 10.0;
            let f = features(m, z);
            let q = quantize(m, f);
            for j in 0..m.values() {
                let v = q[j] + off[j];
                assert!((-1e-5..=1.0 + 1e-5).contains(&v), "{} z {z}: slot {j} = {v}", m.name());
            }
            let back = dequantize(m, q);
            for j in 0..m.values() {
                assert!((back[j] - f[j]).abs() < 2e-5, "{} z {z}: {back:?} vs {f:?}", m.name());
            }
        }
    }
}

#[test]
fn mboit_reconstructs_one_and_two_fragments_within_the_papers_bias() {
    // The moment bound with overestimation 0.25: a fragment sees its own absorbance weighted by
    // 0.25 and all of what is in front: one fragment (T 0.5 at z 0): T = 1 in front, 0.5^0.25
    // at its depth, 0.5 behind; two (T 0.6 at -0.3, T 0.5 at 0.4): 0.6^0.25 at the first,
    // 0.6 * 0.5^0.25 at the second, 0.3 behind both. The 16-bit variants keep b0 in half: add
    // its rounding, 2^-11 of b0, to the bias.
    for m in Moments::ALL {
        let check = |s: &MomentState, z: f32, want: f32| {
            let half = if m.half { want * s.b0 / 2048.0 } else { 0.0 };
            let tol = m.bias() as f32 + 2e-7 + half;
            let got = s.transmittance_at(m, z);
            assert!(
                (got - want).abs() <= tol,
                "{} at {z}: {got} vs {want} (bias {})",
                m.name(),
                m.bias()
            );
        };
        let mut one = MomentState::default();
        one.add(m, 0.0, 0.5);
        check(&one, -0.5, 1.0);
        check(&one, 0.0, 0.5f32.powf(0.25));
        check(&one, 0.5, 0.5);
        let mut two = MomentState::default();
        two.add(m, -0.3, 0.6);
        two.add(m, 0.4, 0.5);
        check(&two, -0.9, 1.0);
        check(&two, -0.3, 0.6f32.powf(0.25));
        check(&two, 0.4, 0.6 * 0.5f32.powf(0.25));
        check(&two, 0.9, 0.3);
    }
}

#[test]
fn mboit_image_of_one_fragment_is_exact_and_of_two_follows_the_bound() {
    let white = [1.0, 1.0, 1.0];
    for m in Moments::ALL {
        // One fragment: sum(c T) / sum(a T) = c / a, times 1 - e^-b0 = a.
        let img = render(Method::Mboit(m), &pixel(&[(2.0, [0.3, 0.1, 0.0], 0.5)], white));
        close(img.rgb[0], [0.3 + 0.5, 0.1 + 0.5, 0.5], 2e-3);
        // Two, far apart: T_front = 0.75^0.25, T_back = 0.75 * 0.5^0.25; C = (c1 T1 + c2 T2) /
        // (a1 T1 + a2 T2) (1 - 0.375) + 0.375 bg.
        let (c1, c2) = ([0.25f32, 0.0, 0.0], [0.0f32, 0.0, 0.5]);
        let img = render(Method::Mboit(m), &pixel(&[(8.0, c2, 0.5), (1.0, c1, 0.25)], white));
        let (t1, t2) = (0.75f32.powf(0.25), 0.75 * 0.5f32.powf(0.25));
        let norm = 0.25 * t1 + 0.5 * t2;
        let want = [0, 1, 2].map(|k| (c1[k] * t1 + c2[k] * t2) / norm * 0.625 + 0.375);
        close(img.rgb[0], want, 3e-3);
        assert!((img.vis[0] - 0.375).abs() < if m.half { 3e-4 } else { 1e-6 });
    }
    // Too little absorbance for the resolve (b0 < 0.0010005): the background only.
    let img = render(
        Method::Mboit(Moments::ALL[0]),
        &pixel(&[(1.0, [0.5, 0.0, 0.0], 0.0009)], white),
    );
    assert_eq!(img.rgb[0], white);
}

#[test]
fn new_methods_memory_is_what_they_store() {
    let s = pixel(&[(1.0, [0.1; 3], 0.5), (2.0, [0.1; 3], 0.5)], [0.0; 3]);
    let b = BinnedStream::new(&s);
    // K-closest: 4 B per layer + the RGBA8 tail.
    for k in [2, 4, 8] {
        assert_eq!(Method::KClosest(k).bytes_per_pixel(&b), (4 * k + 4) as f64);
    }
    // MBOIT: the paper's 112 bits for 6 power moments at 16 bit, plus the RGBA16F target.
    let m6 = Moments::ALL[2];
    assert_eq!((m6.name().as_str(), m6.paper_bits()), ("MBOIT 6 power 16-bit", 112));
    assert_eq!(Method::Mboit(m6).bytes_per_pixel(&b), 14.0 + 8.0);
    assert_eq!(Method::Mboit(Moments::ALL[7]).bytes_per_pixel(&b), 28.0 + 8.0);
    // AT stores every fragment, as the A-buffer: 12 B each + a 4 B head.
    for n in [2, 4, 8] {
        assert_eq!(Method::Adaptive(n).bytes_per_pixel(&b), 4.0 + 12.0 * 2.0);
        assert_eq!(Method::Adaptive(n).storage(), Method::Reference.storage());
    }
    assert!(Method::KClosest(9).render(&b).is_err());
}
