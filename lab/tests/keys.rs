//! The lab keys every fragment it gives the kernel with its primitive's id (issue 30): the
//! MLAB and HT images do not change when every depth changes but no pixel's order does (what
//! a camera move does to a primitive far from the others), and they do change with the ids.

use oit_lab::methods::{Arith, BinnedStream, Image, Method};
use oit_lab::scenes::Scene;
use oit_lab::stream::Stream;

fn render(m: Method, s: &Stream) -> Image {
    m.render(&BinnedStream::new(s)).expect("render")
}

/// The kernel's methods, scalar and through the lanes (the span batcher), both arithmetics.
fn kernel_methods() -> Vec<Method> {
    vec![
        Method::Mlab(1),
        Method::Mlab(4),
        Method::MlabSorted(4),
        Method::MlabLanes(4),
        Method::Hybrid(0),
        Method::Hybrid(3),
        Method::HybridLanes(3),
        Method::MlabWith(4, Arith::Paper),
        Method::HybridWith(3, Arith::Paper),
    ]
}

/// FOG (hundreds of faint fragments per pixel: the faint-fragment dither, and merges) and
/// HAIR (merges of many strands) on small frames.
fn streams() -> Vec<Stream> {
    vec![Scene::Fog.generate(40, 22, 1), Scene::Hair.generate(64, 36, 2)]
}

#[test]
fn kernel_images_hold_still_when_the_depths_move_and_the_order_does_not() {
    for s in streams() {
        // Doubling a positive f32 adds 1 to its exponent: every depth's bits change, every
        // pixel's order and the distances between the depths' keys (the merged depth's
        // arithmetic) do not.
        assert!(s.frags.iter().all(|f| f.depth > 1e-30 && f.depth < 1e30));
        let mut moved = s.clone();
        for f in &mut moved.frags {
            f.depth *= 2.0;
        }
        for m in kernel_methods() {
            assert!(render(m, &s) == render(m, &moved), "{}", m.name());
        }
    }
}

#[test]
fn unbiased_images_follow_the_primitive_ids() {
    for s in streams() {
        let mut renamed = s.clone();
        for f in &mut renamed.frags {
            f.prim = f.prim.wrapping_mul(0x9e37_79b9) ^ 0x5bd1_e995;
        }
        for m in [Method::Mlab(4), Method::MlabLanes(4), Method::Hybrid(3)] {
            assert!(
                render(m, &s) != render(m, &renamed),
                "{}: the ids are not the key",
                m.name()
            );
        }
        // The paper's arithmetic has no dither: the ids change nothing.
        let paper = Method::MlabWith(4, Arith::Paper);
        assert!(render(paper, &s) == render(paper, &renamed));
    }
}
