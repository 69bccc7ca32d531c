//! The lab's exact reference is `mlab_reference::oracle::composite` over the A-buffer's
//! sorted bins (`BinnedStream::sorted`, sorted once and timed as the A-buffer's sort): that order
//! must be the oracle's own (`mlab_reference::oracle::order`), for every scene.

use oit_lab::methods::{BinnedStream, Method};
use oit_lab::scenes::Scene;
use oit_lab::stream::{Frag, Stream};

#[test]
fn sorted_bins_are_the_oracles_order_and_the_reference_is_the_oracle() {
    for sc in Scene::ALL {
        let s = sc.generate(96, 54, 3);
        let binned = BinnedStream::new(&s);
        let img = Method::Reference.render(&binned).expect("reference");
        let bg = s.background.map(f64::from);
        for p in 0..s.pixels() {
            let submitted: Vec<mlab_reference::Layer> = binned
                .bins
                .of(p)
                .iter()
                .map(|&i| {
                    let f = &s.frags[i as usize];
                    mlab_reference::Layer {
                        color: f.color,
                        alpha: f.alpha,
                        depth: f.depth,
                    }
                })
                .collect();
            let want: Vec<u32> = mlab_reference::oracle::order(&submitted)
                .into_iter()
                .map(|k| binned.bins.of(p)[k])
                .collect();
            assert_eq!(binned.sorted.of(p), want.as_slice(), "{} pixel {p}", sc.name());
            let (c, t) = mlab_reference::oracle(&submitted, bg);
            assert_eq!(
                img.rgb[p].map(f32::to_bits),
                c.map(|x| (x as f32).to_bits()),
                "{} pixel {p}",
                sc.name()
            );
            assert_eq!(img.vis[p].to_bits(), (t as f32).to_bits(), "{} pixel {p}", sc.name());
        }
    }
}

/// Ties, signed zeros and the submission order: the A-buffer's sort and the oracle agree
/// on a pixel where every depth ties with another.
#[test]
fn ties_and_signed_zeros() {
    let frags: Vec<Frag> = [(1.0, 0.5), (0.0, 0.25), (1.0, 0.5), (-0.0, 0.75), (0.0, 1.0)]
        .iter()
        .enumerate()
        .map(|(i, &(depth, alpha))| Frag {
            pixel: 0,
            depth,
            color: [0.1 * i as f32 * alpha; 3],
            alpha,
            prim: i as u32,
        })
        .collect();
    let s = Stream {
        width: 1,
        height: 1,
        background: [0.5; 3],
        frags,
    };
    let binned = BinnedStream::new(&s);
    assert_eq!(binned.sorted.of(0), &[4, 3, 1, 2, 0]);
    let layers: Vec<mlab_reference::Layer> = s
        .frags
        .iter()
        .map(|f| mlab_reference::Layer {
            color: f.color,
            alpha: f.alpha,
            depth: f.depth,
        })
        .collect();
    assert_eq!(mlab_reference::oracle::order(&layers), vec![4, 3, 1, 2, 0]);
}
