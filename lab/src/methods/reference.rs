//! The exact A-buffer reference.

use super::{BinnedStream, Image, per_pixel};
use mlab_reference::Layer;

/// The exact reference: `mlab_reference::oracle::composite`, the oracle the kernel's tests
/// and fuzz targets use, over each pixel's fragments as the A-buffer sorted them
/// ([`BinnedStream::sorted`]: front to back, later submission first on equal depth, the oracle's
/// order; the sort is timed apart as `sort_seconds`): in f64 `C += T * c`, `T *= 1 - a`,
/// then `C + T * bg`.
pub(super) fn reference(binned: &BinnedStream) -> Image {
    let (frags, bg) = (&binned.stream.frags, binned.bg().map(f64::from));
    per_pixel(binned, |p| {
        let layers = binned.sorted.of(p).iter().map(|&i| {
            let f = &frags[i as usize];
            Layer {
                color: f.color,
                alpha: f.alpha,
                depth: f.depth,
            }
        });
        let (c, t) = mlab_reference::oracle::composite(layers, bg);
        (c.map(|x| x as f32), t as f32)
    })
}
