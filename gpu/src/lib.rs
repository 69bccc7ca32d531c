//! The same bytes on a GPU: the WGSL twin of the [`mlab`] kernel ([`wgsl`]) and a wgpu
//! compositor ([`Compositor`]) whose rows are bit-identical to the CPU kernel's ([`cpu`]).
//!
//! ```no_run
//! use mlab::Layers;
//! use mlab_gpu::{Arith, Compositor, Gpu, GpuFragment, Layout};
//! let gpu = Gpu::new()?; // the first Vulkan adapter (lavapipe on a machine without a GPU)
//! let compositor = Compositor::new(&gpu, Layers::Mlab(4), Arith::Unbiased, Layout::Spans)?;
//! let fragments = [
//!     GpuFragment::new(5, [0.5, 0.0, 0.0, 0.5], 2.0),
//!     GpuFragment::new(5, [0.01, 0.0, 0.0, 0.03], 3.0).with_key(17), // the primitive's id
//! ];
//! let words = compositor.composite(64, 32, &fragments)?; // the storage, as Row::words
//! assert_eq!(words, mlab_gpu::cpu::composite(Layers::Mlab(4), Arith::Unbiased, Layout::Spans, 64, 32, &fragments)?);
//! # Ok::<(), mlab_gpu::GpuError>(())
//! ```
//!
//! How it works, what it needs and what it guarantees: `docs/gpu.md`.

mod compositor;
pub mod cpu;
mod error;
pub mod wgsl;

pub use compositor::{Compositor, Gpu, GpuFragment, Layout, Sort, background_q15};
pub use error::GpuError;

/// The arithmetic, chosen at run time (the kernel's [`mlab::Paper`] and [`mlab::Unbiased`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Arith {
    /// [`mlab::Paper`]: round to nearest, the paper's tail.
    Paper,
    /// [`mlab::Unbiased`] (the kernel's default): dithered merges and faint fragments (seeded
    /// by each fragment's hash in its pixel, [`mlab::fragment_hash`]), merged rows at their
    /// opacity-weighted depth, the 64-bit [`mlab::Tail`].
    Unbiased,
}

impl Arith {
    /// Both, for loops.
    pub const ALL: [Arith; 2] = [Arith::Paper, Arith::Unbiased];

    /// `"paper"` or `"unbiased"` (as [`mlab::Arithmetic::NAME`]).
    pub const fn name(self) -> &'static str {
        match self {
            Arith::Paper => "paper",
            Arith::Unbiased => "unbiased",
        }
    }
}
