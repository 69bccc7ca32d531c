//! Fragments per covered pixel of a frame ([`depth`]): what the tables print beside each
//! scene (the main job, `oit-lab faint`, `oit-lab stability`).

use super::BinnedStream;

/// Fragments per covered pixel (a pixel is covered when it has at least one fragment).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Depth {
    /// Pixels with at least one fragment.
    pub covered: usize,
    /// Mean fragment count over the covered pixels (0 when none is covered).
    pub mean: f64,
    /// Largest fragment count of a pixel.
    pub max: usize,
}

/// Fragments per covered pixel of a frame.
pub fn depth(binned: &BinnedStream) -> Depth {
    let (mut covered, mut total, mut max) = (0usize, 0usize, 0usize);
    for w in binned.bins.start.windows(2) {
        let n = (w[1] - w[0]) as usize;
        if n > 0 {
            covered += 1;
            total += n;
            max = max.max(n);
        }
    }
    Depth {
        covered,
        mean: if covered > 0 {
            total as f64 / covered as f64
        } else {
            0.0
        },
        max,
    }
}
