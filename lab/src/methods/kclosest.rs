//! K-closest layered OIT as Diligent Engine's Tutorial 29 ("Layered OIT") writes it, after
//! Liu et al.'s FreePipe: the K nearest `(depth, transmittance)` layers per pixel packed into
//! 32-bit integers and kept sorted with atomic min, the rest counted into a tail; a second
//! pass composites each fragment with the transmittance of the layers in front of it.
//!
//! Source: DiligentGraphics/DiligentSamples, `Tutorials/Tutorial29_OIT/` (commit 633b7c5e):
//!
//! - `assets/oit.fxh` lines 1-18: `PackOITLayer` puts `uint(clamp(depth, 0, 1) * 16777215)` in
//!   the high 24 bits and `uint(clamp(T, 0, 1) * 255)` (truncated) in the low 8, so that the
//!   packed values sort by depth ([`pack`]);
//! - `assets/update_oit_layers.psh` lines 30-64: a fragment with opacity above
//!   `OPACITY_THRESHOLD = 1/255` (`assets/common.fxh` line 27) is packed and inserted with
//!   `InterlockedMin` into the K slots in order; an empty slot (`0xFFFFFFFF`) or an identical
//!   value ends the insert, otherwise the larger of the two goes on to the next slot; the value
//!   left over after the K slots goes to the tail: an RGBA8 target (`Tutorial29_OIT.hpp` line
//!   75) whose R channel adds `1/255` per tail layer and whose A channel multiplies by the
//!   layer's 8-bit transmittance (blend state `BS_UpdateOITTail`, `Tutorial29_OIT.cpp` lines
//!   59-75) ([`Layers::insert`]);
//! - `assets/attenuate_background.psh` lines 20-40: the background is multiplied by the
//!   product of the stored layers' transmittances and, when all K are used, the tail's A;
//! - `assets/layered_oit_blend.psh` lines 24-53: each fragment's premultiplied color is
//!   multiplied by the product of the transmittances of the layers whose depth is below its own
//!   minus one unit (`D <= LayerD + 1` stops), and, when it is behind all K, divided by the tail
//!   count (`T /= max(255 * Tail.x, 1)`, "average contribution of all tail layers"); the
//!   results are added to the target ([`Layers::transmittance`]).
//!
//! Memory: `4 K` bytes of layers and the 4-byte RGBA8 tail, `4 K + 4` B/px.
//!
//! Departures, each named:
//! - depth: the lab's fragments carry view distance, the sample `SV_Position.z`; the lab maps
//!   view distance to window depth with the perspective mapping WBOIT's eq. 10 uses (near and
//!   far at the stream's depth range widened by 10 %), then packs it as the sample does;
//! - a fragment at or below the opacity threshold is not stored (as in the sample) but is
//!   composited with the transmittance of the layers in front of it; the sample adds it with
//!   `T = 1`, harmless there because its colors are premultiplied by that alpha (at most
//!   1/255), not for the lab's additive light (alpha 0, color > 0);
//! - the sample adds the composited colors into the swap chain's back buffer; the lab adds them
//!   in f64 (exact for these magnitudes, so the sum does not depend on the order) and writes the
//!   result once to half, as the lab's AT does. The layers and the tail are emulated bit for bit.

use super::baselines::{r8_blend, window_depth};
use super::{BinnedStream, Image, f16r, per_pixel};

/// Largest K supported.
pub const KCLOSEST_MAX: usize = 8;

/// An empty layer slot (the clear value of `clear_oit_layers.csh`).
pub const EMPTY: u32 = 0xFFFF_FFFF;

/// Fragments at or below this opacity are not stored (`OPACITY_THRESHOLD`, common.fxh line 27).
pub const OPACITY_THRESHOLD: f32 = 1.0 / 255.0;

/// `PackOITLayer`: 24-bit depth (window depth in `[0, 1]`, truncated) over 8-bit
/// transmittance (truncated).
pub fn pack(depth01: f32, transmittance: f32) -> u32 {
    let d = (depth01.clamp(0.0, 1.0) * 16_777_215.0) as u32;
    let t = (transmittance.clamp(0.0, 1.0) * 255.0) as u32;
    (d << 8) | t
}

/// The 24-bit depth of a packed layer.
pub fn layer_depth(layer: u32) -> u32 {
    layer >> 8
}

/// The transmittance of a packed layer.
pub fn layer_transmittance(layer: u32) -> f32 {
    (layer & 0xFF) as f32 / 255.0
}

/// One pixel's K layers and its RGBA8 tail.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Layers {
    /// The slots, sorted ascending (empty slots, `EMPTY`, last); only the first K are used.
    pub slots: [u32; KCLOSEST_MAX],
    /// The tail's R channel: tail layers counted in units of 1/255 (saturates at 255).
    pub tail_count: u8,
    /// The tail's A channel: the product of the tail layers' transmittances, unorm8.
    pub tail_t: u8,
    /// K.
    pub k: usize,
}

impl Layers {
    /// Cleared: every slot empty, the tail `(0, 0, 0, 1)`.
    pub fn new(k: usize) -> Layers {
        Layers {
            slots: [EMPTY; KCLOSEST_MAX],
            tail_count: 0,
            tail_t: 255,
            k: k.clamp(1, KCLOSEST_MAX),
        }
    }

    /// Insert a packed layer: the atomic-min chain of `update_oit_layers.psh`, then the tail
    /// blend for what is left over.
    pub fn insert(&mut self, packed: u32) {
        let mut layer = packed;
        for slot in &mut self.slots[..self.k] {
            let orig = *slot;
            *slot = orig.min(layer);
            if orig == EMPTY || orig == layer {
                layer = EMPTY;
                break;
            }
            layer = layer.max(orig);
        }
        if layer != EMPTY {
            // R: Src * 1 + Dst * 1 with Src = 1/255 (unorm8, saturating).
            self.tail_count = self.tail_count.saturating_add(1);
            // A: Src * 0 + Dst * SrcA with SrcA = the layer's transmittance.
            self.tail_t = r8_blend(self.tail_t, layer_transmittance(layer));
        }
    }

    /// The transmittance a fragment at 24-bit depth `d` is composited with
    /// (`layered_oit_blend.psh` lines 26-51).
    pub fn transmittance(&self, d: u32) -> f32 {
        let mut t = 1.0f32;
        let mut i = 0;
        while i < self.k {
            let l = self.slots[i];
            if d <= layer_depth(l) + 1 {
                break;
            }
            t *= layer_transmittance(l);
            i += 1;
        }
        if i == self.k {
            t /= (self.tail_count as f32).max(1.0);
        }
        t
    }

    /// The background's transmittance (`attenuate_background.psh` lines 21-35).
    pub fn background(&self) -> f32 {
        let mut t = 1.0f32;
        let mut i = 0;
        while i < self.k {
            let l = self.slots[i];
            if l == EMPTY {
                break;
            }
            t *= layer_transmittance(l);
            i += 1;
        }
        if i == self.k {
            t *= self.tail_t as f32 / 255.0;
        }
        t
    }
}

/// K-closest layered OIT over the pixel's fragments in submission order (see the module).
pub(super) fn kclosest(binned: &BinnedStream, k: usize) -> Image {
    let (frags, bg, nf) = (&binned.stream.frags, binned.bg(), binned.near_far);
    per_pixel(binned, |p| {
        let mut layers = Layers::new(k);
        for &i in binned.bins.of(p) {
            let f = &frags[i as usize];
            if f.alpha > OPACITY_THRESHOLD {
                layers.insert(pack(window_depth(f.depth, nf), 1.0 - f.alpha));
            }
        }
        let tb = layers.background();
        let mut c = [0.0f64; 3];
        for &i in binned.bins.of(p) {
            let f = &frags[i as usize];
            let d = (window_depth(f.depth, nf) * 16_777_215.0) as u32;
            let t = layers.transmittance(d);
            for (ck, &fk) in c.iter_mut().zip(&f.color) {
                *ck += (fk * t) as f64;
            }
        }
        let rgb = std::array::from_fn(|ch| f16r((c[ch] + (bg[ch] * tb) as f64) as f32));
        (rgb, tb)
    })
}
