//! The compositor's input: one fragment as the GPU reads it.

use bytemuck::{Pod, Zeroable};

/// One fragment for [`Compositor::composite`](crate::Compositor::composite): its pixel (`y * width + x`), premultiplied linear
/// `[R, G, B, A]` and depth, as [`mlab::Fragment::premultiplied_rgba`] takes them (validated the
/// same way), and optionally a stable key ([`mlab::Fragment::with_key`]: the primitive's id,
/// which seeds [`mlab::Unbiased`]'s dithers so that they do not re-roll from frame to frame).
///
/// The layout is what the GPU reads (8 words, `composite.wgsl`), so a renderer that writes
/// fragments from a shader writes the same words: `keyed` is a `u32` flag rather than an
/// `Option` for that reason. Build one with [`GpuFragment::new`] and
/// [`with_key`](GpuFragment::with_key).
///
/// ```
/// use mlab_gpu::GpuFragment;
/// let f = GpuFragment::new(5, [0.02, 0.0, 0.0, 0.02], 2.0).with_key(42);
/// assert_eq!(f.key(), Some(42));
/// assert_eq!(GpuFragment::new(5, [0.0; 4], 2.0).key(), None); // the content key seeds it
/// ```
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct GpuFragment {
    /// `y * width + x`: where it is inserted, and the pixel id of its hash
    /// ([`mlab::fragment_hash`]; the kernel's `Framebuffer::pixel_id`).
    pub pixel: u32,
    /// Premultiplied color and alpha.
    pub rgba: [f32; 4],
    /// Depth (smaller = nearer).
    pub depth: f32,
    /// The stable key, read only when `keyed` is not 0.
    pub key: u32,
    /// Not 0: `key` is the fragment's stable key ([`mlab::Fragment::with_key`]); 0: it has
    /// none, and its dithers are seeded with its content key (the XOR of the bits of its five
    /// f32, [`mlab::Fragment::hash`]), which changes with its depth.
    pub keyed: u32,
}

impl GpuFragment {
    /// A fragment without a stable key.
    pub const fn new(pixel: u32, rgba: [f32; 4], depth: f32) -> GpuFragment {
        GpuFragment {
            pixel,
            rgba,
            depth,
            key: 0,
            keyed: 0,
        }
    }

    /// This fragment with the stable key `key` (as [`mlab::Fragment::with_key`]).
    #[must_use]
    pub const fn with_key(self, key: u32) -> GpuFragment {
        GpuFragment { key, keyed: 1, ..self }
    }

    /// The stable key, if it has one (`keyed` not 0).
    pub const fn key(&self) -> Option<u32> {
        if self.keyed != 0 { Some(self.key) } else { None }
    }
}
