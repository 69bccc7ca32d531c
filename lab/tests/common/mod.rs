//! The 1x1 helpers of the hand-computed method tests (methods.rs, peers.rs).
#![allow(dead_code)]

use oit_lab::methods::{BinnedStream, Image, Method};
use oit_lab::stream::{Frag, Stream};

/// A 1x1 stream from `(depth, premultiplied color, alpha)` in submission order, each
/// fragment its own primitive (its index).
pub fn pixel(frags: &[(f32, [f32; 3], f32)], bg: [f32; 3]) -> Stream {
    let frags = frags
        .iter()
        .enumerate()
        .map(|(i, &(depth, color, alpha))| Frag {
            pixel: 0,
            depth,
            color,
            alpha,
            prim: i as u32,
        })
        .collect();
    Stream {
        width: 1,
        height: 1,
        background: bg,
        frags,
    }
}

pub fn render(m: Method, s: &Stream) -> Image {
    m.render(&BinnedStream::new(s)).expect("render")
}

pub fn close(got: [f32; 3], want: [f32; 3], tol: f32) {
    for k in 0..3 {
        assert!(
            (got[k] - want[k]).abs() <= tol,
            "channel {k}: got {got:?}, want {want:?} (tol {tol})"
        );
    }
}
