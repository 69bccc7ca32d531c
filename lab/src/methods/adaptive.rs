//! Adaptive Transparency (Salvi et al. 2011), two passes, as Intel's published AOIT sample.

// Channel loops `for k in 0..3` index several arrays at once (target, fragment, weight);
// written as in the blend equations.
#![allow(clippy::needless_range_loop)]

use super::{BinnedStream, Image, f16r, over_bg, per_pixel};

/// Adaptive Transparency's visibility function: nodes `(z, T)` sorted front to back, where
/// `T` is the visibility just behind `z` (seed 002: "a sorted (front-to-back) sequence of
/// nodes stored into a fixed-size array", the first node `(0, 1)` implicit).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Visibility {
    /// The nodes, front to back.
    pub nodes: Vec<(f32, f32)>,
}

/// The first node AT may remove when it keeps `n` nodes: Intel's published AOIT code
/// protects the front half of the nodes from removal when `n >= 8` ("to bias our compression
/// scheme in order to favor the closest nodes to the eye we skip the first 50%"), and
/// otherwise only node 0.
///
/// Source: GameTechDev/AOIT-Update, `OIT_DX11/AOIT Technique/DXAOIT.hlsl` (commit 7a637f28,
/// the two-pass AT of the sample: fragment lists, then a visibility function per pixel),
/// lines 24-27 (`AOIT_DONT_COMPRESS_FIRST_HALF` for `OIT_NODE_COUNT >= 8`) and 219-225
/// (`startRemovalIdx = removalCandidateCount / 2`, else 1, with `removalCandidateCount = N`).
/// The sample builds only multiples of 4 nodes (`OIT_RT_COUNT = N / 4`, line 20); AT 1 and
/// AT 2 here follow the same rule (start at node 1).
pub fn at_first_removable(n: usize) -> usize {
    if n >= 8 { n / 2 } else { 1 }
}

impl Visibility {
    /// Insert a fragment of alpha `a` at depth `z` and compress, as the published AOIT code
    /// does (DXAOIT.hlsl `AOITInsertFragment`, lines 173-267; see [`at_first_removable`]):
    ///
    /// - every fragment is inserted, alpha 0 included (a purely additive one makes a node
    ///   that keeps the visibility of the node in front), in front of the nodes at its depth
    ///   (`fragmentDepth <= depth[i]` ends the search, lines 145-163); the nodes behind it
    ///   are attenuated by `1 - a` (lines 196-211);
    /// - with `n + 1` nodes (line 214), the node `i` in `at_first_removable(n)..n` with the
    ///   smallest area variation `(z_i - z_(i-1)) * (T_(i-1) - T_i)` is removed, the front
    ///   one on ties (lines 217-245): the last node, the farthest, is never a candidate;
    /// - node `i - 1` takes `T_i` and node `i` goes (lines 247-257): visibility is
    ///   underestimated, never overestimated.
    pub fn insert(&mut self, z: f32, a: f32, n: usize) {
        let n = n.max(1);
        let pos = self
            .nodes
            .iter()
            .position(|&(nz, _)| nz >= z)
            .unwrap_or(self.nodes.len());
        let before = if pos == 0 { 1.0 } else { self.nodes[pos - 1].1 };
        let t = 1.0 - a;
        self.nodes.insert(pos, (z, t * before));
        for node in &mut self.nodes[pos + 1..] {
            node.1 *= t;
        }
        while self.nodes.len() > n {
            let last = self.nodes.len() - 1;
            let area = |i: usize| (self.nodes[i].0 - self.nodes[i - 1].0) * (self.nodes[i - 1].1 - self.nodes[i].1);
            // The sample starts from the first candidate and keeps it unless a later one is
            // strictly smaller (with one node, no candidate: node 1, the last, goes).
            let mut best = at_first_removable(n);
            if best < last {
                let mut best_area = area(best);
                for i in best + 1..last {
                    let ai = area(i);
                    if ai < best_area {
                        best_area = ai;
                        best = i;
                    }
                }
            }
            self.nodes[best - 1].1 = self.nodes[best].1;
            self.nodes.remove(best);
        }
    }

    /// Visibility at depth `z`: `T` of the last node strictly in front of `z`, else 1 (the
    /// published resolve, DX_Resolve.hlsl lines 62-63).
    pub fn at(&self, z: f32) -> f32 {
        self.nodes
            .iter()
            .take_while(|&&(nz, _)| nz < z)
            .last()
            .map_or(1.0, |&(_, t)| t)
    }

    /// Visibility behind everything (of the background).
    pub fn total(&self) -> f32 {
        self.nodes.last().map_or(1.0, |&(_, t)| t)
    }
}

/// Adaptive Transparency, two passes, as the published resolve (GameTechDev/AOIT-Update,
/// `OIT_DX11/AOIT Technique/DX_Resolve.hlsl`, commit 7a637f28, lines 25-71): build the
/// visibility function with `n` nodes over the pixel's fragments in submission order, then
/// `C = sum(c * vis(z))` in f32 registers, written once to an RGBA16F target, plus
/// `bg * vis(inf)`. The departures from the sample: fragments keep their f32 color and alpha
/// (the sample reads them back from RGBA8 fragment lists), and `n` may be 1 or 2.
pub(super) fn adaptive(binned: &BinnedStream, n: usize) -> Image {
    let (frags, bg) = (&binned.stream.frags, binned.bg());
    per_pixel(binned, |p| {
        let mut v = Visibility {
            nodes: Vec::with_capacity(n + 1),
        };
        for &i in binned.bins.of(p) {
            let f = &frags[i as usize];
            v.insert(f.depth, f.alpha, n);
        }
        let mut c = [0.0f32; 3];
        for &i in binned.bins.of(p) {
            let f = &frags[i as usize];
            let vis = v.at(f.depth);
            for k in 0..3 {
                c[k] += f.color[k] * vis;
            }
        }
        let t = v.total();
        (over_bg(c.map(f16r), t, bg), t)
    })
}
